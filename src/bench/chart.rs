//! Log-log line charts for the benchmarks, written as PNG and SVG with plotters.
//! The font ships inside the binary (DejaVu Sans), so charts need no system fonts.

use plotters::coord::combinators::WithKeyPoints;
use plotters::prelude::*;
use std::path::Path;
use std::sync::Once;

/// Evaluates `$body` with `$m` a function from a point to marker `$shape` (circle,
/// triangle, square, cross; see [`MARKERS`]) in `$color`: a macro, as each shape is
/// its own type and plotters' boxed elements do not fit its series' lifetimes.
macro_rules! with_marker {
    ($shape:expr, $color:expr, |$m:ident| $body:expr) => {{
        let color: RGBAColor = $color;
        match $shape % MARKERS {
            0 => {
                let $m = |p| Circle::new(p, 4, color.filled());
                $body
            }
            1 => {
                let $m = |p| TriangleMarker::new(p, 5, color.filled());
                $body
            }
            2 => {
                let $m =
                    |p| EmptyElement::at(p) + Rectangle::new([(-3, -3), (3, 3)], color.filled());
                $body
            }
            _ => {
                let $m = |p| Cross::new(p, 4, color.stroke_width(2));
                $body
            }
        }
    }};
}

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

/// Tick values of a log axis over `lo..hi`: `(labelled, grid only)`. plotters' own
/// log ticks start at the first power of ten inside the range, so a range below it
/// (0.02 to 0.3) shows no number under 0.1, and one within a decade shows none at
/// all. Here every decade is labelled, and 1-2-5 or every integer mantissa in
/// narrower ranges; the other mantissas draw light grid lines.
fn log_ticks(lo: f64, hi: f64) -> (Vec<f64>, Vec<f64>) {
    let (lo, hi) = (lo.min(hi), lo.max(hi));
    if !(lo > 0.0 && hi.is_finite()) {
        return (Vec::new(), Vec::new());
    }
    let decades = (hi / lo).log10();
    let labelled: &[u32] = match decades {
        d if d <= 0.6 => &[1, 2, 3, 4, 5, 6, 7, 8, 9],
        d if d <= 2.5 => &[1, 2, 5],
        _ => &[1],
    };
    // Past 8 decades, a label on every k-th power of ten keeps them apart.
    let every = (decades / 8.0).ceil().max(1.0) as i32;
    let (first, last) = (lo.log10().floor() as i32, hi.log10().ceil() as i32);
    let (mut bold, mut light) = (Vec::new(), Vec::new());
    for e in first..=last {
        for m in 1..=9 {
            let v = f64::from(m) * 10f64.powi(e);
            if v < lo || v > hi {
                continue;
            }
            if labelled.contains(&m) && (m != 1 || e.rem_euclid(every) == 0) {
                bold.push(v);
            } else {
                light.push(v);
            }
        }
    }
    (bold, light)
}

/// A logarithmic axis over `lo..hi` ticked by [`log_ticks`].
fn log_axis(lo: f64, hi: f64) -> WithKeyPoints<LogCoord<f64>> {
    let (bold, light) = log_ticks(lo, hi);
    (lo..hi)
        .log_scale()
        .with_key_points(bold)
        .with_light_points(light)
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

/// Both files; `legend` is the width of the legend column beside the 900-pixel plot.
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
    draw_legend(&side, series)?;
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
                let (color, shape) = series_style(i);
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
                    .map_err(|e| anyhow::anyhow!("chart: {e}"))?;
                with_marker!(shape, color, |m| chart
                    .draw_series(pts.iter().map(|&p| m(p)))
                    .map(|_| ())
                    .map_err(|e| anyhow::anyhow!("chart: {e}"))?);
            }
        }};
    }
    match (spec.log_x, spec.log_y) {
        (true, true) => {
            finish!(builder.build_cartesian_2d(log_axis(x0, x1), log_axis(y0, y1)))
        }
        (true, false) => finish!(builder.build_cartesian_2d(log_axis(x0, x1), y0..y1)),
        (false, true) => finish!(builder.build_cartesian_2d(x0..x1, log_axis(y0, y1))),
        (false, false) => finish!(builder.build_cartesian_2d(x0..x1, y0..y1)),
    }
    root.present().map_err(|e| anyhow::anyhow!("chart: {e}"))?;
    Ok(())
}

/// Ten colours that stay apart on white (Tableau 10, its olive darkened).
const PALETTE: [(u8, u8, u8); 10] = [
    (31, 119, 180),
    (255, 127, 14),
    (44, 160, 44),
    (214, 39, 40),
    (148, 103, 189),
    (140, 86, 75),
    (227, 119, 194),
    (127, 127, 127),
    (150, 150, 20),
    (23, 190, 207),
];

/// How many marker shapes [`with_marker`] draws.
const MARKERS: usize = 4;

/// The `i`-th series' colour and marker shape. The shape advances with every series
/// and once more each time the colours come round, so the first 40 series all differ
/// (a converge chart has 14).
fn series_style(i: usize) -> (RGBAColor, usize) {
    let (r, g, b) = PALETTE[i % PALETTE.len()];
    (
        RGBColor(r, g, b).to_rgba(),
        (i + i / PALETTE.len()) % MARKERS,
    )
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
        let (color, shape) = series_style(i);
        let y = 60 + 22 * i as i32;
        area.draw(&PathElement::new(
            vec![(5, y), (30, y)],
            color.stroke_width(2),
        ))
        .and_then(|_| with_marker!(shape, color, |m| area.draw(&m((17, y)))))
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
        // Integer ranges are inclusive: 0..n-1 is n slots, one per case, no empty
        // slot (and unlabelled tick) after the last.
        .build_cartesian_2d((0..n - 1).into_segmented(), log_axis(y0, y1))
        .map_err(err)?;
    debug_assert!(spec.log_y, "category charts have a logarithmic y axis");
    chart
        .configure_mesh()
        .x_desc(spec.x_label)
        .y_desc(spec.y_label)
        .x_labels(categories.len())
        .label_style(("sans-serif", 13))
        .x_label_formatter(&label)
        .y_label_formatter(&|v| tick(*v))
        .disable_x_mesh()
        .draw()
        .map_err(err)?;
    for (k, s) in series.iter().enumerate() {
        let color = series_style(k).0;
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
    fn series_styles_differ() {
        let styles: Vec<_> = (0..40).map(series_style).collect();
        for (i, a) in styles.iter().enumerate() {
            for b in &styles[..i] {
                assert!(a.0 != b.0 || a.1 != b.1, "series {i} repeats a style");
            }
        }
    }

    #[test]
    fn log_ticks_label_below_the_first_decade() {
        // A small-error range: plotters alone labels only 0.1 here.
        let (bold, light) = log_ticks(0.02, 0.3);
        assert_eq!(bold.len(), 4, "{bold:?}");
        assert!((bold[0] - 0.02).abs() < 1e-12 && (bold[3] - 0.2).abs() < 1e-12);
        assert!(light.iter().any(|v| (v - 0.03).abs() < 1e-12));
        // Within one decade: every integer mantissa.
        let (bold, _) = log_ticks(0.031, 0.07);
        assert_eq!(bold.len(), 4, "{bold:?}");
        // Wide ranges: powers of ten only, at most about eight.
        let (bold, _) = log_ticks(1e-3, 1e3);
        assert_eq!(bold.len(), 7, "{bold:?}");
        let (bold, _) = log_ticks(1e-9, 1e9);
        assert!((2..=10).contains(&bold.len()), "{bold:?}");
    }

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
        // Beside the plot: the image widens by the legend column, whose names are there.
        write_chart_legend_outside(&stem, &spec, &s).unwrap();
        let png = image::open(stem.with_extension("png")).unwrap();
        assert!(png.width() > 900, "{}", png.width());
        let svg = std::fs::read_to_string(stem.with_extension("svg")).unwrap();
        assert!(svg.contains("RMSE") && svg.contains("<svg"));
        let label = |name: &str| svg.lines().any(|l| l.trim() == name);
        assert!(label("a") && label("b"), "{svg}");
    }
}
