//! Log-log line charts for the benchmarks, written as PNG and SVG with plotters.
//! The font ships inside the binary (DejaVu Sans), so charts need no system fonts.

use plotters::prelude::*;
use std::path::Path;
use std::sync::Once;

/// One line of a chart.
#[derive(Clone, Debug)]
pub struct Series {
    pub name: String,
    pub points: Vec<(f64, f64)>,
}

pub struct ChartSpec<'a> {
    pub title: &'a str,
    pub x_label: &'a str,
    pub y_label: &'a str,
    pub log_x: bool,
    pub log_y: bool,
}

/// Short tick labels: log axes otherwise print values like 0.30000000000000004.
fn tick(v: f64) -> String {
    let a = v.abs();
    if a == 0.0 {
        "0".into()
    } else if (1e-3..1e5).contains(&a) {
        let s = format!("{:.3}", v);
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        format!("{v:.1e}")
    }
}

fn register_font() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        // Registration can only fail on a malformed font; the embedded one is fine.
        let _ = plotters::style::register_font(
            "sans-serif",
            FontStyle::Normal,
            dejavu::sans::regular(),
        );
    });
}

/// Writes the chart to `stem.png` and `stem.svg`, its legend inside the plot.
pub fn write_chart(stem: &Path, spec: &ChartSpec, series: &[Series]) -> anyhow::Result<()> {
    write_both(stem, spec, series, 0)
}

/// Writes the chart to `stem.png` and `stem.svg` with its legend in a column right of
/// the plot, where it covers no curve however many there are.
pub fn write_chart_legend_outside(
    stem: &Path,
    spec: &ChartSpec,
    series: &[Series],
) -> anyhow::Result<()> {
    let longest = series.iter().map(|s| s.name.chars().count()).max();
    // About 7.5 px per character at the legend's 14 px, plus the line sample.
    let legend = longest.map_or(0, |n| 50 + (n as u32 * 15).div_ceil(2));
    write_both(stem, spec, series, legend)
}

/// Both files; `legend` > 0 is the width of a legend column beside the 900-pixel plot.
fn write_both(stem: &Path, spec: &ChartSpec, series: &[Series], legend: u32) -> anyhow::Result<()> {
    register_font();
    let png = stem.with_extension("png");
    let svg = stem.with_extension("svg");
    let (width, height) = (900 + legend, 600);
    let mut rgb = vec![0u8; (width * height * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut rgb, (width, height)).into_drawing_area();
        draw(root, spec, series, legend)?;
    }
    write_png(&png, &rgb, width, height)?;
    {
        let root = SVGBackend::new(&svg, (width, height)).into_drawing_area();
        draw(root, spec, series, legend)?;
    }
    Ok(())
}

/// Best compression: charts are committed to the repository, and line art
/// compresses far better than the encoder's fast default.
fn write_png(path: &Path, rgb: &[u8], width: u32, height: u32) -> anyhow::Result<()> {
    use image::codecs::png::{CompressionType, FilterType, PngEncoder};
    use image::ImageEncoder;
    let file = std::io::BufWriter::new(std::fs::File::create(path)?);
    PngEncoder::new_with_quality(file, CompressionType::Best, FilterType::Adaptive).write_image(
        rgb,
        width,
        height,
        image::ExtendedColorType::Rgb8,
    )?;
    Ok(())
}

fn bounds(series: &[Series], pick: impl Fn(&(f64, f64)) -> f64, log: bool) -> (f64, f64) {
    let vals = series
        .iter()
        .flat_map(|s| s.points.iter().map(&pick))
        .filter(|v| v.is_finite() && (!log || *v > 0.0));
    let (mut lo, mut hi) = vals.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
        (a.min(v), b.max(v))
    });
    if !lo.is_finite() {
        (lo, hi) = (1.0, 10.0);
    }
    if log {
        (lo / 1.5, hi * 1.5)
    } else {
        let pad = (hi - lo).abs().max(1e-9) * 0.05;
        (lo - pad, hi + pad)
    }
}

fn draw<DB: DrawingBackend>(
    root: DrawingArea<DB, plotters::coord::Shift>,
    spec: &ChartSpec,
    series: &[Series],
    legend: u32,
) -> anyhow::Result<()>
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE)
        .map_err(|e| anyhow::anyhow!("chart: {e}"))?;
    let (plot, side) = root.split_horizontally(root.dim_in_pixel().0 - legend);
    if legend > 0 {
        draw_legend(&side, series)?;
    }
    let root = plot;
    let (x0, x1) = bounds(series, |p| p.0, spec.log_x);
    let (y0, y1) = bounds(series, |p| p.1, spec.log_y);
    let mut builder = ChartBuilder::on(&root);
    builder
        .caption(spec.title, ("sans-serif", 24))
        .margin(15)
        .x_label_area_size(50)
        .y_label_area_size(80);
    macro_rules! finish {
        ($chart:expr) => {{
            let mut chart = $chart.map_err(|e| anyhow::anyhow!("chart: {e}"))?;
            chart
                .configure_mesh()
                .x_desc(spec.x_label)
                .y_desc(spec.y_label)
                .label_style(("sans-serif", 14))
                .x_label_formatter(&|v| tick(*v))
                .y_label_formatter(&|v| tick(*v))
                .draw()
                .map_err(|e| anyhow::anyhow!("chart: {e}"))?;
            for (i, s) in series.iter().enumerate() {
                let color = series_color(i);
                let pts: Vec<(f64, f64)> = s
                    .points
                    .iter()
                    .copied()
                    .filter(|p| {
                        p.0.is_finite()
                            && p.1.is_finite()
                            && (!spec.log_x || p.0 > 0.0)
                            && (!spec.log_y || p.1 > 0.0)
                    })
                    .collect();
                chart
                    .draw_series(LineSeries::new(pts.clone(), color.stroke_width(2)))
                    .map_err(|e| anyhow::anyhow!("chart: {e}"))?
                    .label(s.name.clone())
                    .legend(move |(x, y)| {
                        PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2))
                    });
                chart
                    .draw_series(pts.into_iter().map(|p| Circle::new(p, 3, color.filled())))
                    .map_err(|e| anyhow::anyhow!("chart: {e}"))?;
            }
            if legend == 0 {
                chart
                    .configure_series_labels()
                    .background_style(WHITE.mix(0.85))
                    .border_style(BLACK)
                    .label_font(("sans-serif", 14))
                    .draw()
                    .map_err(|e| anyhow::anyhow!("chart: {e}"))?;
            }
        }};
    }
    match (spec.log_x, spec.log_y) {
        (true, true) => {
            finish!(builder.build_cartesian_2d((x0..x1).log_scale(), (y0..y1).log_scale()))
        }
        (true, false) => finish!(builder.build_cartesian_2d((x0..x1).log_scale(), y0..y1)),
        (false, true) => finish!(builder.build_cartesian_2d(x0..x1, (y0..y1).log_scale())),
        (false, false) => finish!(builder.build_cartesian_2d(x0..x1, y0..y1)),
    }
    root.present().map_err(|e| anyhow::anyhow!("chart: {e}"))?;
    Ok(())
}

/// The palette's `i`-th colour, darkened where it is too pale to read on white.
fn series_color(i: usize) -> RGBAColor {
    let c = Palette99::pick(i).to_rgba();
    let luma = 0.299 * f64::from(c.0) + 0.587 * f64::from(c.1) + 0.114 * f64::from(c.2);
    if luma > 170.0 {
        let dark = |v: u8| (f64::from(v) * 0.6) as u8;
        RGBAColor(dark(c.0), dark(c.1), dark(c.2), c.3)
    } else {
        c
    }
}

/// One row per series, in the chart's colours, from the top of `area`.
fn draw_legend<DB: DrawingBackend>(
    area: &DrawingArea<DB, plotters::coord::Shift>,
    series: &[Series],
) -> anyhow::Result<()>
where
    DB::ErrorType: 'static,
{
    let font = ("sans-serif", 14).into_font().color(&BLACK);
    for (i, s) in series.iter().enumerate() {
        let color = series_color(i);
        let y = 60 + 22 * i as i32;
        area.draw(&PathElement::new(
            vec![(5, y), (30, y)],
            color.stroke_width(2),
        ))
        .and_then(|_| area.draw(&Circle::new((17, y), 3, color.filled())))
        .and_then(|_| area.draw(&Text::new(s.name.clone(), (38, y - 8), font.clone())))
        .map_err(|e| anyhow::anyhow!("chart: {e}"))?;
    }
    Ok(())
}

/// A chart of values per category (cases of a table, not points of a scale): each
/// category is a slot of the x axis labelled with its name, each series a marker of
/// its own shape and colour in every slot it has a value for; y is logarithmic
/// (`spec.log_y` must be set). `series` points are `(category index, value)`.
pub fn write_category_chart(
    stem: &Path,
    spec: &ChartSpec,
    categories: &[String],
    series: &[Series],
) -> anyhow::Result<()> {
    register_font();
    let (width, height) = (1100, 600);
    let mut rgb = vec![0u8; (width * height * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut rgb, (width, height)).into_drawing_area();
        draw_categories(root, spec, categories, series)?;
    }
    write_png(&stem.with_extension("png"), &rgb, width, height)?;
    let svg = stem.with_extension("svg");
    let root = SVGBackend::new(&svg, (width, height)).into_drawing_area();
    draw_categories(root, spec, categories, series)
}

fn draw_categories<DB: DrawingBackend>(
    root: DrawingArea<DB, plotters::coord::Shift>,
    spec: &ChartSpec,
    categories: &[String],
    series: &[Series],
) -> anyhow::Result<()>
where
    DB::ErrorType: 'static,
{
    let err = |e: DrawingAreaErrorKind<DB::ErrorType>| anyhow::anyhow!("chart: {e}");
    root.fill(&WHITE).map_err(err)?;
    let (y0, y1) = bounds(series, |p| p.1, spec.log_y);
    // Headroom above the highest marker for the legend.
    let y1 = if spec.log_y {
        y1 * 10.0
    } else {
        y1 + (y1 - y0) * 0.3
    };
    let n = categories.len().max(1) as i32;
    let label = |v: &SegmentValue<i32>| match v {
        SegmentValue::CenterOf(i) => categories.get(*i as usize).cloned().unwrap_or_default(),
        _ => String::new(),
    };
    let mut chart = ChartBuilder::on(&root)
        .caption(spec.title, ("sans-serif", 22))
        .margin(15)
        .x_label_area_size(60)
        .y_label_area_size(80)
        .build_cartesian_2d((0..n).into_segmented(), (y0..y1).log_scale())
        .map_err(err)?;
    debug_assert!(spec.log_y, "category charts have a logarithmic y axis");
    chart
        .configure_mesh()
        .x_desc(spec.x_label)
        .y_desc(spec.y_label)
        .x_labels(categories.len() + 1)
        .label_style(("sans-serif", 13))
        .x_label_formatter(&label)
        .y_label_formatter(&|v| tick(*v))
        .disable_x_mesh()
        .draw()
        .map_err(err)?;
    for (k, s) in series.iter().enumerate() {
        let color = Palette99::pick(k).to_rgba();
        let pts: Vec<(SegmentValue<i32>, f64)> = s
            .points
            .iter()
            .filter(|p| p.1.is_finite() && (!spec.log_y || p.1 > 0.0))
            .map(|&(x, y)| (SegmentValue::CenterOf(x as i32), y))
            .collect();
        // Shapes differ so that equal values of two series stay visible.
        let size = [9, 8, 6, 5][k % 4];
        let (solid, line) = (color.filled(), color.stroke_width(3));
        macro_rules! markers {
            ($at:expr, $legend:expr) => {
                chart
                    .draw_series(pts.iter().cloned().map($at))
                    .map_err(err)?
                    .label(s.name.clone())
                    .legend($legend)
            };
        }
        match k % 4 {
            0 => markers!(|p| Circle::new(p, size, solid), move |(x, y)| Circle::new(
                (x + 8, y),
                5,
                solid
            )),
            1 => markers!(|p| Cross::new(p, size, line), move |(x, y)| Cross::new(
                (x + 8, y),
                5,
                line
            )),
            2 => markers!(
                |p| EmptyElement::at(p) + Rectangle::new([(-size, -size), (size, size)], line),
                move |(x, y)| Rectangle::new([(x + 3, y - 5), (x + 13, y + 5)], line)
            ),
            _ => markers!(|p| TriangleMarker::new(p, size, solid), move |(x, y)| {
                TriangleMarker::new((x + 8, y), 6, solid)
            }),
        };
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font(("sans-serif", 14))
        .draw()
        .map_err(err)?;
    root.present().map_err(err)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn writes_png_and_svg() {
        let dir = tempfile::tempdir().unwrap();
        let stem = dir.path().join("c");
        let s = vec![
            Series {
                name: "a".into(),
                points: vec![(1.0, 1.0), (2.0, 0.5), (4.0, 0.25)],
            },
            Series {
                name: "b".into(),
                points: vec![(1.0, 2.0), (2.0, 1.0), (4.0, 0.6)],
            },
        ];
        let spec = ChartSpec {
            title: "t",
            x_label: "time (s)",
            y_label: "RMSE",
            log_x: true,
            log_y: true,
        };
        write_chart(&stem, &spec, &s).unwrap();
        let png = image::open(stem.with_extension("png")).unwrap();
        assert_eq!(png.width(), 900);
        let svg = std::fs::read_to_string(stem.with_extension("svg")).unwrap();
        assert!(svg.contains("RMSE") && svg.contains("<svg"));
        // Beside the plot: the image widens by the legend column, whose names are there.
        write_chart_legend_outside(&stem, &spec, &s).unwrap();
        let png = image::open(stem.with_extension("png")).unwrap();
        assert!(png.width() > 900, "{}", png.width());
        let svg = std::fs::read_to_string(stem.with_extension("svg")).unwrap();
        let label = |name: &str| svg.lines().any(|l| l.trim() == name);
        assert!(label("a") && label("b"), "{svg}");
    }
}
