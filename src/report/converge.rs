//! Section 6: error against render time for each method, from `ember bench
//! converge`, against the Mitsuba 3 reference of the scene, with Mitsuba 3 itself as a
//! method when it is installed.

use super::page::{Block, Figure, FigureRow, TableBlock};
use super::plan::{stem, Budget, ConvergeCase};
use super::recipe::shell_word;
use super::{shell_path, Progress, ReportOptions};
use crate::bench::converge::{self, ConvergeOptions, MitsubaPeer};
use crate::bench::mitsuba::MitsubaRunner;
use crate::bench::Report;
use crate::export::{MitsubaRoulette, MitsubaSampler};
use anyhow::Result;
use std::path::{Path, PathBuf};

/// The Mitsuba variant of the curves (the references' own).
const MITSUBA_VARIANT: &str = "llvm_ad_rgb";
/// The references' resolution, at which the runs render.
const SIZE: (u32, u32) = (160, 120);

/// Work units of one run, as many as a quarter of a full render's pixels per point
/// (the run reports only when a method starts).
pub(super) fn work(b: &Budget) -> u64 {
    METHOD_UNITS * 8 * (1 + b.converge_max_spp.ilog2() as u64)
}

const METHOD_UNITS: u64 = 10_000;

/// The run's charts and tables, or why a peer is missing.
pub(super) fn blocks(
    case: &ConvergeCase,
    opts: &ReportOptions,
    b: &Budget,
    progress: &dyn Progress,
) -> Result<Vec<Block>> {
    let out_dir = opts.out.join("converge");
    let mut blocks = Vec::new();
    let (mitsuba, note) = mitsuba_peer(opts, &out_dir);
    let (reference, reference_noise) = reference(case)?;
    let copts = ConvergeOptions {
        scene: case.scene.clone(),
        reference: reference.clone(),
        reference_noise,
        width: SIZE.0,
        height: SIZE.1,
        max_depth: case.max_depth,
        max_spp: b.converge_max_spp,
        max_seconds_per_point: b.converge_max_seconds,
        reference_spp: if opts.quick { 256 } else { 4096 },
        out_dir: out_dir.clone(),
        seed: opts.seed,
        seeds: 1,
        compare_backends: true,
        mitsuba: mitsuba.clone(),
        cycles: None,
    };
    let share = work(b);
    let mut reported = 0;
    let report = converge::run(&copts, &mut |line| {
        if line.starts_with("method:") && reported + share / 8 <= share {
            progress.advance(share / 8);
            reported += share / 8;
        }
    })?;
    progress.advance(share - reported);
    let files = report.write(&out_dir)?;
    let reference_note = report.reference_note.trim_end_matches('.');
    blocks.push(Block::Text(format!(
        "{}: `-m {}`, {}×{}, each point a fresh render at twice the samples of the last, until {} spp or {} s. Against the {reference_note}. {note}",
        stem(&case.scene),
        case.max_depth,
        SIZE.0,
        SIZE.1,
        b.converge_max_spp,
        b.converge_max_seconds,
    )));
    let command = command(&copts);
    let charts = files
        .iter()
        .filter(|f| f.extension().is_some_and(|e| e == "png"));
    blocks.push(Block::Figures(FigureRow {
        caption: format!(
            "{}, -m {}: error against render time",
            stem(&case.scene),
            case.max_depth
        ),
        figures: charts
            .map(|f| chart(f, &opts.out, &command))
            .collect::<Result<_>>()?,
    }));
    for table in [report.equal_time_table(), report.equal_spp_table()] {
        if let Some(t) = table_from_markdown(&table) {
            blocks.push(Block::Table(t));
        }
    }
    Ok(blocks)
}

/// Mitsuba 3 as a method when `opts.mitsuba` names a Python that runs it, and a
/// sentence saying which curves the charts have.
fn mitsuba_peer(opts: &ReportOptions, dir: &Path) -> (Option<MitsubaPeer>, String) {
    let Some(python) = &opts.mitsuba else {
        return (
            None,
            "Mitsuba 3 is not installed, so the charts show ember's methods only \
             (`scripts/mitsuba-env` installs it; `ember report --mitsuba PYTHON` uses it)."
                .into(),
        );
    };
    let probe = MitsubaRunner::new(
        python,
        MITSUBA_VARIANT,
        MitsubaSampler::default(),
        MitsubaRoulette::Ember,
        &dir.join("mitsuba"),
    );
    match probe {
        Ok(_) => (
            Some(MitsubaPeer {
                python: python.clone(),
                variants: vec![MITSUBA_VARIANT.into()],
                // Its best sampler only, to keep the report's time.
                samplers: vec![MitsubaSampler::default()],
                roulettes: vec![MitsubaRoulette::Ember],
            }),
            format!("Mitsuba 3 ({MITSUBA_VARIANT}) renders the same scene as a peer method on this machine."),
        ),
        Err(e) => (
            None,
            format!("Mitsuba 3 could not run ({e:#}), so the charts show ember's methods only."),
        ),
    }
}

/// The scene's Mitsuba reference and its per-pixel noise, if the data folder has one.
fn reference(case: &ConvergeCase) -> Result<(Option<PathBuf>, Option<f64>)> {
    let Some(file) = &case.reference else {
        return Ok((None, None));
    };
    let path = crate::data::references()?.join(file);
    let noise = crate::bench::stability::light_paths::manifest_noise(&path)?;
    Ok((Some(path), noise))
}

/// The `ember bench converge` command that runs the same measurement (its times, and
/// so its curves, differ from run to run).
fn command(o: &ConvergeOptions) -> String {
    let mut w = vec![
        "ember".to_string(),
        "bench".into(),
        "converge".into(),
        shell_path(&o.scene),
        "-m".into(),
        o.max_depth.to_string(),
    ];
    if let (Some(r), Some(n)) = (&o.reference, o.reference_noise) {
        w.extend(["--reference".into(), shell_path(r)]);
        w.extend(["--reference-noise".into(), format!("{n:.5}")]);
    } else {
        w.extend(["--reference-spp".into(), o.reference_spp.to_string()]);
    }
    w.extend(["--max-spp".into(), o.max_spp.to_string()]);
    w.extend(["--max-seconds".into(), o.max_seconds_per_point.to_string()]);
    if o.seed != 0 {
        w.extend(["--seed".into(), o.seed.to_string()]);
    }
    if let Some(m) = &o.mitsuba {
        w.extend(["--mitsuba".into(), shell_path(&m.python)]);
    }
    w.extend(["--out".into(), shell_path(&o.out_dir)]);
    let quoted: Vec<String> = w.iter().map(|s| shell_word(s)).collect();
    quoted.join(" ")
}

fn chart(file: &Path, page_dir: &Path, command: &str) -> Result<Figure> {
    let (width, height) = image::image_dimensions(file)
        .map_err(|e| anyhow::anyhow!("{}: cannot read: {e}", file.display()))?;
    let rel = file.strip_prefix(page_dir).unwrap_or(file);
    let name = rel.to_string_lossy().replace('\\', "/");
    let label = match name.contains("relmse") {
        true => "relative MSE against time",
        false => "RMSE against time",
    };
    Ok(Figure {
        image: name,
        label: label.into(),
        width,
        height,
        commands: vec![command.to_string()],
        note: "times differ from run to run".into(),
    })
}

/// A GitHub Markdown table (header, rule, rows) as a table block.
fn table_from_markdown(md: &str) -> Option<TableBlock> {
    let cells = |line: &str| -> Vec<String> {
        let inner = line.trim().trim_start_matches('|').trim_end_matches('|');
        inner.split('|').map(|c| c.trim().to_string()).collect()
    };
    let mut lines = md.lines().filter(|l| l.trim_start().starts_with('|'));
    let header = cells(lines.next()?);
    let rows: Vec<Vec<String>> = lines.skip(1).map(cells).collect();
    Some(TableBlock {
        caption: String::new(),
        header,
        rows,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn markdown_tables_read_back() {
        let t = table_from_markdown("| a | b |\n|---|---|\n| 1 | 2 |\n").unwrap();
        assert_eq!(t.header, ["a", "b"]);
        assert_eq!(t.rows, [["1", "2"]]);
        assert!(table_from_markdown("").is_none());
    }
}
