//! The storage-versus-speed scatter of the hybrid-voxel-formats paper: every structure of
//! `naadf bench paper` as a point at (bytes, Mrays/s), primary and secondary rays in two
//! colours and shapes, each labelled with the structure's name. Both axes are logarithmic:
//! sizes span orders of magnitude, and speeds of about 0.5–50 Mrays/s read as ratios, so
//! a structure that is twice as fast sits the same distance higher wherever it is. The
//! point of the plot is the trade-off the paper argues about: lower-left is small but
//! slow, upper-left is what everyone wants. Structures that are only counted, not
//! traversed (the dense grid of a world too large to decode), have bytes but no speed;
//! they are drawn as labelled ticks on the x axis so their size can still be compared.
//!
//! Drawn with plotters' bitmap backend into a buffer that `image` encodes as PNG. Text
//! uses ab_glyph with a TrueType font read at run time (see [`draw_scatter`] for where it
//! is looked for), so no fontconfig or other system library is needed.

use anyhow::{Context, Result, anyhow, bail};
use image::ImageEncoder;
use plotters::backend::RGBPixel;
use plotters::coord::combinators::{LogCoord, WithKeyPoints};
use plotters::prelude::*;
use plotters::style::{FontStyle, register_font};
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

/// One structure's point on the scatter.
pub struct Point {
    /// The structure's name, drawn next to its markers.
    pub name: String,
    /// Its size in bytes (x axis); must be positive.
    pub bytes: u64,
    /// Primary-ray throughput in Mrays/s, or `None` when not measured.
    pub primary: Option<f64>,
    /// Secondary-ray throughput in Mrays/s, or `None` when not measured.
    pub secondary: Option<f64>,
}

/// Width of the PNG in pixels.
const WIDTH: u32 = 900;
/// Height of the PNG in pixels.
const HEIGHT: u32 = 600;
/// The environment variable that names the TTF file to draw text with.
const FONT_ENV: &str = "NAADF_PLOT_FONT";
/// Where a sans-serif TTF is looked for when `NAADF_PLOT_FONT` is unset: DejaVu Sans and
/// Liberation Sans as Debian/Ubuntu, Arch and Fedora install them, then macOS's Arial.
const FONT_PATHS: &[&str] = &[
    "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf",
    "/usr/share/fonts/TTF/DejaVuSans.ttf",
    "/usr/share/fonts/dejavu/DejaVuSans.ttf",
    "/usr/share/fonts/dejavu-sans-fonts/DejaVuSans.ttf",
    "/usr/share/fonts/truetype/liberation/LiberationSans-Regular.ttf",
    "/usr/share/fonts/liberation/LiberationSans-Regular.ttf",
    "/usr/share/fonts/liberation-sans/LiberationSans-Regular.ttf",
    "/usr/share/fonts/TTF/LiberationSans-Regular.ttf",
    "/System/Library/Fonts/Supplemental/Arial.ttf",
];
/// The family plotters' default styles (axis labels, legend) ask for.
const FAMILY: &str = "sans-serif";

/// Primary-ray markers (blue).
const PRIMARY: RGBColor = RGBColor(31, 119, 180);
/// Secondary-ray markers (orange).
const SECONDARY: RGBColor = RGBColor(214, 96, 39);
/// Counted-only ticks on the x axis (grey).
const COUNTED: RGBColor = RGBColor(110, 110, 110);
/// The structures' name labels.
const LABEL: RGBColor = RGBColor(40, 40, 40);

/// Draws bytes (x, log scale) against Mrays/s (y, log scale) as a 900×600 PNG at `out`:
/// one marker per structure and ray kind (primary: blue circles, secondary: orange
/// triangles, with a legend), each labelled with the structure's name; the title names
/// `world`. Points without a speed are drawn as labelled grey ticks on the x axis
/// ("counted only" in the legend); a point with only one speed gets only that marker.
///
/// Text needs a TrueType font, read once per process: the file named by the environment
/// variable `NAADF_PLOT_FONT` if it is set, else the first of DejaVu Sans or Liberation
/// Sans found in the usual system paths (Debian's `fonts-dejavu-core` provides one).
///
/// Errors (never panics) when `points` is empty, a point has zero bytes or a speed that is
/// not a positive finite number, no font can be found or parsed, or `out` cannot be written.
pub fn draw_scatter(world: &str, points: &[Point], out: &Path) -> Result<()> {
    if points.is_empty() {
        bail!("no points to plot for {world}");
    }
    for p in points {
        if p.bytes == 0 {
            bail!("{}: 0 bytes cannot be placed on a log axis", p.name);
        }
        for (kind, v) in [("primary", p.primary), ("secondary", p.secondary)] {
            if let Some(v) = v
                && !(v.is_finite() && v > 0.0)
            {
                bail!("{}: {kind} speed {v} Mrays/s is not a positive number", p.name);
            }
        }
    }
    ensure_font()?;

    let mut buf = vec![255u8; (WIDTH * HEIGHT * 3) as usize];
    render(world, points, &mut buf).context("drawing the scatter")?;

    let file = std::fs::File::create(out).with_context(|| format!("cannot create {}", out.display()))?;
    let mut w = std::io::BufWriter::new(file);
    image::codecs::png::PngEncoder::new(&mut w)
        .write_image(&buf, WIDTH, HEIGHT, image::ExtendedColorType::Rgb8)
        .with_context(|| format!("cannot write the PNG {}", out.display()))?;
    std::io::Write::flush(&mut w).with_context(|| format!("cannot write {}", out.display()))?;
    Ok(())
}

/// Registers the plot font with plotters once per process (see [`draw_scatter`]).
fn ensure_font() -> Result<()> {
    static REGISTERED: OnceLock<PathBuf> = OnceLock::new();
    if REGISTERED.get().is_some() {
        return Ok(());
    }
    let candidates: Vec<PathBuf> = FONT_PATHS.iter().map(PathBuf::from).collect();
    let (path, bytes) = find_font(std::env::var_os(FONT_ENV), &candidates)?;
    // plotters keeps fonts for the life of the process; this runs once, so leaking is fine.
    let bytes: &'static [u8] = Box::leak(bytes.into_boxed_slice());
    register_font(FAMILY, FontStyle::Normal, bytes).map_err(|_| {
        anyhow!(
            "{} is not a usable TrueType/OpenType font; set {FONT_ENV} to another .ttf",
            path.display()
        )
    })?;
    let _ = REGISTERED.set(path);
    Ok(())
}

/// Reads the font named by `env_override` (the value of `NAADF_PLOT_FONT`), or else the
/// first readable file of `candidates`; the error names every path tried and the fix.
fn find_font(env_override: Option<std::ffi::OsString>, candidates: &[PathBuf]) -> Result<(PathBuf, Vec<u8>)> {
    if let Some(p) = env_override.filter(|p| !p.is_empty()) {
        let p = PathBuf::from(p);
        let bytes = std::fs::read(&p).with_context(|| format!("cannot read the font {FONT_ENV}={}", p.display()))?;
        return Ok((p, bytes));
    }
    for p in candidates {
        if let Ok(bytes) = std::fs::read(p) {
            return Ok((p.clone(), bytes));
        }
    }
    let tried: Vec<String> = candidates.iter().map(|p| p.display().to_string()).collect();
    bail!(
        "no font found for the plot's text (tried {}); install fonts-dejavu-core \
         (apt-get install fonts-dejavu-core) or set {FONT_ENV} to a .ttf file",
        tried.join(", ")
    )
}

/// A marker's or label's box in pixels: x0, y0, x1, y1.
type Bbox = (i32, i32, i32, i32);

/// Where a label goes, relative to its marker: beside it for plotted points, above it for
/// the ticks on the x axis.
#[derive(Clone, Copy)]
enum Anchor {
    Beside,
    Above,
}

/// Draws the chart into `buf` (RGB, `WIDTH`×`HEIGHT`).
fn render(world: &str, points: &[Point], buf: &mut [u8]) -> Result<()> {
    let root = BitMapBackend::<RGBPixel>::with_buffer_and_format(buf, (WIDTH, HEIGHT))
        .map_err(|e| anyhow!("{e}"))?
        .into_drawing_area();
    root.fill(&WHITE).map_err(plot_err)?;

    let speeds: Vec<f64> = points.iter().flat_map(|p| [p.primary, p.secondary]).flatten().collect();
    let counted: Vec<&Point> = points
        .iter()
        .filter(|p| p.primary.is_none() && p.secondary.is_none())
        .collect();

    let (x_lo, x_hi) = log_range(points.iter().map(|p| p.bytes as f64), 0.2, 0.0);
    // Room at the bottom for the counted-only ticks and their labels.
    let band = if counted.is_empty() { 0.0 } else { 0.15 };
    let (y_lo, y_hi) = if speeds.is_empty() {
        (0.1, 100.0)
    } else {
        log_range(speeds.iter().copied(), 0.15, band)
    };
    // No speed ticks in that band (nor at all without speeds): its markers have no speed.
    let y_ticks_from = if speeds.is_empty() {
        f64::INFINITY
    } else {
        log_range(speeds.iter().copied(), 0.15, 0.0).0
    };

    let mut chart = ChartBuilder::on(&root)
        .caption(format!("{world}: storage vs. ray speed"), (FAMILY, 24))
        .margin(16)
        .x_label_area_size(50)
        .y_label_area_size(64)
        .build_cartesian_2d(log_axis(x_lo, x_hi, x_lo), log_axis(y_lo, y_hi, y_ticks_from))
        .map_err(plot_err)?;
    chart
        .configure_mesh()
        .x_desc("bytes (log scale)")
        .y_desc("Mrays/s (log scale)")
        .axis_desc_style((FAMILY, 16))
        .label_style((FAMILY, 13))
        .x_label_formatter(&|v| format_bytes(*v))
        .y_label_formatter(&|v| format_number(*v))
        .light_line_style(RGBColor(236, 236, 236))
        .bold_line_style(RGBColor(200, 200, 200))
        .draw()
        .map_err(plot_err)?;

    let primary: Vec<(f64, f64)> = points
        .iter()
        .filter_map(|p| Some((p.bytes as f64, p.primary?)))
        .collect();
    let secondary: Vec<(f64, f64)> = points
        .iter()
        .filter_map(|p| Some((p.bytes as f64, p.secondary?)))
        .collect();

    // Every marker's pixel box, so that labels avoid markers as well as each other.
    let mut taken: Vec<Bbox> = Vec::new();
    // (name, marker box, where the label goes)
    let mut labels: Vec<(&str, Bbox, Anchor)> = Vec::new();
    for p in points {
        for v in [p.primary, p.secondary].into_iter().flatten() {
            let (x, y) = chart.backend_coord(&(p.bytes as f64, v));
            let b = (x - 6, y - 6, x + 6, y + 6);
            taken.push(b);
            labels.push((&p.name, b, Anchor::Beside));
        }
    }
    for p in &counted {
        let (x, y) = chart.backend_coord(&(p.bytes as f64, y_lo));
        let b = (x - 6, y - 22, x + 6, y);
        taken.push(b);
        labels.push((&p.name, b, Anchor::Above));
    }

    if !primary.is_empty() {
        chart
            .draw_series(primary.iter().map(|&c| Circle::new(c, 5, PRIMARY.filled())))
            .map_err(plot_err)?
            .label("primary rays")
            .legend(|(x, y)| Circle::new((x, y), 5, PRIMARY.filled()));
    }
    if !secondary.is_empty() {
        chart
            .draw_series(secondary.iter().map(|&c| TriangleMarker::new(c, 7, SECONDARY.filled())))
            .map_err(plot_err)?
            .label("secondary rays")
            .legend(|(x, y)| TriangleMarker::new((x, y), 7, SECONDARY.filled()));
    }
    if !counted.is_empty() {
        chart
            .draw_series(counted.iter().map(|p| {
                EmptyElement::at((p.bytes as f64, y_lo))
                    + PathElement::new(vec![(0, 0), (0, -10)], COUNTED.stroke_width(2))
                    + Polygon::new(diamond((0, -16), 6), COUNTED.filled())
            }))
            .map_err(plot_err)?
            .label("counted only (no speed)")
            .legend(|c| Polygon::new(diamond(c, 6), COUNTED.filled()));
    }

    let (area_x, area_y) = chart.plotting_area().get_pixel_range();
    let area: Bbox = (area_x.start, area_y.start, area_x.end, area_y.end);
    let legend_pos = legend_corner(area, &taken);

    let style = TextStyle::from((FAMILY, 14).into_font()).color(&LABEL);
    for (name, marker, anchor) in &labels {
        let (w, h) = root.estimate_text_size(name, &style).map_err(plot_err)?;
        let at = place_label(*marker, (w as i32, h as i32), *anchor, area, &taken);
        taken.push((at.0, at.1, at.0 + w as i32, at.1 + h as i32));
        root.draw(&Text::new(name.to_string(), at, style.clone()))
            .map_err(plot_err)?;
    }

    chart
        .configure_series_labels()
        .position(legend_pos)
        .margin(10)
        .label_font((FAMILY, 14))
        .background_style(WHITE.mix(0.9))
        .border_style(RGBColor(160, 160, 160))
        .draw()
        .map_err(plot_err)?;
    root.present().map_err(plot_err)?;
    Ok(())
}

/// Turns a plotters drawing error into an anyhow one.
fn plot_err<E: std::fmt::Display>(e: E) -> anyhow::Error {
    anyhow!("{e}")
}

/// The axis range for `values` on a log scale: at least 1.2 decades wide (so there is a
/// power of ten to label), padded by `pad` of the span at each end and by `extra_below`
/// more at the bottom.
fn log_range(values: impl Iterator<Item = f64>, pad: f64, extra_below: f64) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in values {
        lo = lo.min(v.log10());
        hi = hi.max(v.log10());
    }
    let mid = (lo + hi) / 2.0;
    let half = ((hi - lo) / 2.0).max(0.6);
    let span = 2.0 * half;
    let lo = mid - half - pad * span - extra_below * span;
    let hi = mid + half + pad * span;
    (10f64.powf(lo), 10f64.powf(hi))
}

/// A log axis over `lo..hi` whose labelled ticks are 1, 2 and 5 times powers of ten when
/// it spans at most three decades, and powers of ten (every so many when there are many)
/// otherwise; the light grid lines mark 1–9 times each power of ten. Neither goes below
/// `ticks_from`.
fn log_axis(lo: f64, hi: f64, ticks_from: f64) -> WithKeyPoints<LogCoord<f64>> {
    let (first, last) = (lo.log10().floor() as i32, hi.log10().ceil() as i32);
    let decades = hi.log10() - lo.log10();
    let (mantissas, step): (&[f64], i32) = if decades <= 3.0 {
        (&[1.0, 2.0, 5.0], 1)
    } else {
        (&[1.0], (decades / 8.0).ceil().max(1.0) as i32)
    };
    let inside = |v: &f64| (ticks_from.max(lo)..=hi).contains(v);
    let bold: Vec<f64> = (first..=last)
        .filter(|e| e.rem_euclid(step) == 0)
        .flat_map(|e| mantissas.iter().map(move |m| m * 10f64.powi(e)))
        .filter(inside)
        .collect();
    let light: Vec<f64> = if decades <= 8.0 {
        (first..=last)
            .flat_map(|e| (1..10).map(move |m| f64::from(m) * 10f64.powi(e)))
            .filter(inside)
            .collect()
    } else {
        Vec::new()
    };
    (lo..hi).log_scale().with_key_points(bold).with_light_points(light)
}

/// A diamond's corners around `c`, `r` pixels from the centre.
fn diamond(c: (i32, i32), r: i32) -> Vec<(i32, i32)> {
    vec![(c.0, c.1 - r), (c.0 + r, c.1), (c.0, c.1 + r), (c.0 - r, c.1)]
}

/// Overlap area of two boxes (0 when they do not touch).
fn overlap(a: Bbox, b: Bbox) -> i64 {
    let w = (a.2.min(b.2) - a.0.max(b.0)).max(0) as i64;
    let h = (a.3.min(b.3) - a.1.max(b.1)).max(0) as i64;
    w * h
}

/// The top-left corner for a `size` label next to `marker`: the first candidate position
/// inside `area` that overlaps nothing in `taken`, else the one that overlaps least.
fn place_label(marker: Bbox, size: (i32, i32), anchor: Anchor, area: Bbox, taken: &[Bbox]) -> (i32, i32) {
    let (w, h) = size;
    let (x0, y0, x1, y1) = marker;
    let (cx, cy) = ((x0 + x1) / 2, (y0 + y1) / 2);
    let gap = 4;
    let right = x1 + gap;
    let left = x0 - gap - w;
    let centre = cx - w / 2;
    let above = y0 - gap - h;
    let below = y1 + gap;
    let mid = cy - h / 2;
    let candidates: Vec<(i32, i32)> = match anchor {
        Anchor::Beside => vec![
            (right, mid),
            (left, mid),
            (centre, above),
            (centre, below),
            (right, above),
            (right, below),
            (left, above),
            (left, below),
            (right, above - h),
            (right, below + h),
            (left, above - h),
            (left, below + h),
        ],
        Anchor::Above => vec![
            (centre, above),
            (right, above + h / 2),
            (left, above + h / 2),
            (centre, above - h),
            (right, above - h / 2),
            (left, above - h / 2),
            (centre, above - 2 * h),
        ],
    };
    let score = |&(x, y): &(i32, i32)| -> i64 {
        let b = (x, y, x + w, y + h);
        let outside = (w as i64 * h as i64) - overlap(b, area);
        // Leaving the plot is worse than touching a neighbour's label.
        outside * 4 + taken.iter().map(|&t| overlap(b, t)).sum::<i64>()
    };
    let mut best = candidates[0];
    let mut best_score = i64::MAX;
    for c in &candidates {
        let s = score(c);
        if s == 0 {
            return *c;
        }
        if s < best_score {
            best = *c;
            best_score = s;
        }
    }
    best
}

/// The legend corner of `area` whose quarter holds the fewest markers.
fn legend_corner(area: Bbox, markers: &[Bbox]) -> SeriesLabelPosition {
    let (x0, y0, x1, y1) = area;
    // The legend is about 230×90 pixels; count what lies under a box a bit larger.
    let (w, h) = (260, 110);
    let corners = [
        (SeriesLabelPosition::UpperLeft, (x0, y0, x0 + w, y0 + h)),
        (SeriesLabelPosition::UpperRight, (x1 - w, y0, x1, y0 + h)),
        (SeriesLabelPosition::LowerRight, (x1 - w, y1 - h, x1, y1)),
        (SeriesLabelPosition::LowerLeft, (x0, y1 - h, x0 + w, y1)),
    ];
    let mut best = (SeriesLabelPosition::UpperLeft, usize::MAX);
    for (pos, b) in corners {
        let n = markers.iter().filter(|&&m| overlap(m, b) > 0).count();
        if n < best.1 {
            best = (pos, n);
        }
    }
    best.0
}

/// A byte count as a short label with a decimal unit: "100 kB", "2.5 MB".
fn format_bytes(v: f64) -> String {
    const UNITS: [&str; 6] = ["B", "kB", "MB", "GB", "TB", "PB"];
    let mut v = v;
    let mut unit = 0;
    while v >= 999.5 && unit + 1 < UNITS.len() {
        v /= 1000.0;
        unit += 1;
    }
    format!("{} {}", format_number(v), UNITS[unit])
}

/// A positive number to at most three significant digits, without trailing zeros.
fn format_number(v: f64) -> String {
    let decimals = if v >= 100.0 {
        0
    } else if v >= 10.0 {
        1
    } else if v >= 1.0 {
        2
    } else {
        // Three significant digits below 1: 0.5 -> 3 decimals, 0.05 -> 4.
        (3 - v.log10().floor() as i32 - 1).clamp(0, 8) as usize
    };
    let s = format!("{v:.decimals$}");
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn point(name: &str, bytes: u64, primary: Option<f64>, secondary: Option<f64>) -> Point {
        Point {
            name: name.to_string(),
            bytes,
            primary,
            secondary,
        }
    }

    #[test]
    fn draws_a_readable_scatter() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("scatter.png");
        let points = [
            point("naadf", 48_000_000, Some(42.0), Some(11.5)),
            point("svo", 9_500_000, Some(6.2), Some(1.9)),
            point("svdag", 2_100_000, Some(3.1), Some(0.6)),
            point("R(4³)G(7)", 1_300_000, None, None),
        ];
        draw_scatter("sponza", &points, &out).unwrap();

        let img = image::open(&out).unwrap().to_rgb8();
        assert_eq!(img.dimensions(), (WIDTH, HEIGHT));
        let first = *img.get_pixel(0, 0);
        assert!(img.pixels().any(|p| *p != first), "the PNG is a single colour");
        // Markers in both series' colours made it into the picture.
        for colour in [PRIMARY, SECONDARY, COUNTED] {
            let want = image::Rgb([colour.0, colour.1, colour.2]);
            assert!(img.pixels().any(|p| *p == want), "no pixel of {colour:?} in the plot");
        }
    }

    #[test]
    fn empty_points_is_an_error() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("empty.png");
        let err = draw_scatter("sponza", &[], &out).unwrap_err();
        assert!(err.to_string().contains("no points"), "{err:#}");
        assert!(!out.exists());
    }

    #[test]
    fn missing_font_names_the_paths_and_the_fix() {
        let dir = tempfile::tempdir().unwrap();
        let missing = [dir.path().join("a.ttf"), dir.path().join("b.ttf")];
        let err = find_font(None, &missing).unwrap_err().to_string();
        for p in &missing {
            assert!(err.contains(&p.display().to_string()), "{err}");
        }
        assert!(err.contains("fonts-dejavu-core") && err.contains(FONT_ENV), "{err}");

        let over = dir.path().join("override.ttf");
        let err = find_font(Some(over.clone().into_os_string()), &missing).unwrap_err();
        assert!(format!("{err:#}").contains(FONT_ENV), "{err:#}");
    }

    #[test]
    fn unwritable_output_is_an_error() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("no-such-dir").join("scatter.png");
        let points = [point("naadf", 1_000, Some(1.0), None)];
        let err = draw_scatter("w", &points, &out).unwrap_err();
        assert!(format!("{err:#}").contains("no-such-dir"), "{err:#}");
    }

    #[test]
    fn labels_read_well() {
        assert_eq!(format_bytes(1e6), "1 MB");
        assert_eq!(format_bytes(2.5e4), "25 kB");
        assert_eq!(format_bytes(500.0), "500 B");
        assert_eq!(format_number(0.5), "0.5");
        assert_eq!(format_number(20.0), "20");
        assert_eq!(format_number(1.25), "1.25");
    }
}
