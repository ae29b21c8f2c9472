//! The evaluation's PNG figures (drawn with plotters into a buffer, text in
//! the DejaVu Sans font shipped in `cli/assets/fonts`, encoded with png):
//! distance per episode, h_b over the phase angle per terrain type (the
//! paper's Fig. 4), and the target landing height per foot per terrain type.

use std::path::Path;
use std::sync::OnceLock;

use anyhow::{Context, Result, anyhow};
use plotters::prelude::*;

use super::record::EpisodeRecord;
use super::summary::{TerrainSummary, angle_bin_centre_deg};

/// Width and height of every figure, pixels.
pub const FIGURE_SIZE_PX: (u32, u32) = (1024, 640);

/// The figure files, in the order they are written.
pub const FIGURE_FILES: [&str; 3] = [
    "distance.png",
    "base_height_phase.png",
    "landing_height.png",
];

/// The family name the built-in font is registered under.
pub(crate) const FONT: &str = "sans-serif";
static FONT_BYTES: &[u8] = include_bytes!("../../assets/fonts/DejaVuSans.ttf");

const COLOURS: [RGBColor; 8] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
];

/// Registers the built-in font (once) for text drawn with plotters.
pub(crate) fn register_font() -> Result<()> {
    static REGISTERED: OnceLock<bool> = OnceLock::new();
    let ok = *REGISTERED.get_or_init(|| {
        plotters::style::register_font(FONT, FontStyle::Normal, FONT_BYTES).is_ok()
    });
    if ok {
        Ok(())
    } else {
        Err(anyhow!("the built-in plot font could not be loaded"))
    }
}

/// Draws with `draw` into an RGB buffer of [`FIGURE_SIZE_PX`] and writes it
/// to `path` as PNG.
fn render(
    path: &Path,
    draw: impl FnOnce(&DrawingArea<BitMapBackend<'_>, plotters::coord::Shift>) -> Result<()>,
) -> Result<()> {
    register_font()?;
    let (w, h) = FIGURE_SIZE_PX;
    let mut rgb = vec![0u8; (w * h * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut rgb, (w, h)).into_drawing_area();
        root.fill(&WHITE).map_err(plot_error)?;
        draw(&root)?;
        root.present().map_err(plot_error)?;
    }
    let file = std::fs::File::create(path).with_context(|| format!("{}", path.display()))?;
    let mut encoder = png::Encoder::new(std::io::BufWriter::new(file), w, h);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    let mut writer = encoder
        .write_header()
        .with_context(|| format!("{}", path.display()))?;
    writer
        .write_image_data(&rgb)
        .with_context(|| format!("{}", path.display()))?;
    writer
        .finish()
        .with_context(|| format!("{}", path.display()))?;
    Ok(())
}

/// The plotting backend's errors, as text.
fn plot_error(e: impl std::fmt::Display) -> anyhow::Error {
    anyhow!("{e}")
}

type Chart<'a, 'b> = ChartContext<
    'a,
    BitMapBackend<'b>,
    Cartesian2d<plotters::coord::types::RangedCoordf64, plotters::coord::types::RangedCoordf64>,
>;

/// A titled chart over `x` and `y` filling `root`.
fn new_chart<'a, 'b>(
    root: &'a DrawingArea<BitMapBackend<'b>, plotters::coord::Shift>,
    title: &str,
    x: std::ops::Range<f64>,
    y: std::ops::Range<f64>,
) -> Result<Chart<'a, 'b>> {
    ChartBuilder::on(root)
        .caption(title, (FONT, 22))
        .margin(16)
        .x_label_area_size(44)
        .y_label_area_size(64)
        .build_cartesian_2d(x, y)
        .map_err(plot_error)
}

/// The legend of the series drawn with labels, top left.
fn draw_legend<'a, 'b: 'a>(chart: &mut Chart<'a, 'b>) -> Result<()> {
    chart
        .configure_series_labels()
        .label_font((FONT, 15))
        .position(SeriesLabelPosition::UpperLeft)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()
        .map_err(plot_error)
}

/// A tick label: a whole number with thousands separated ("100,000", not
/// plotters' "100000.0"), anything else to at most two decimals without
/// trailing zeros ("0.5", "1.25").
fn tick_label(value: f64) -> String {
    if value.fract() == 0.0 && value.abs() < 1e15 {
        let digits = format!("{}", value.abs() as u64);
        let mut grouped = String::new();
        for (i, c) in digits.chars().enumerate() {
            if i > 0 && (digits.len() - i) % 3 == 0 {
                grouped.push(',');
            }
            grouped.push(c);
        }
        return if value < 0.0 {
            format!("-{grouped}")
        } else {
            grouped
        };
    }
    let text = format!("{value:.2}");
    let text = text.trim_end_matches('0').trim_end_matches('.');
    if text == "-0" {
        "0".to_string()
    } else {
        text.to_string()
    }
}

/// A range around `values` with a margin (a unit range when empty or flat).
fn padded_range(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) = values
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
            (lo.min(v), hi.max(v))
        });
    if !lo.is_finite() {
        return (0.0, 1.0);
    }
    let pad = ((hi - lo) * 0.1).max(0.05);
    (lo - pad, hi + pad)
}

/// Distance along x of each episode: blue ran every phase, red fell.
pub fn distance_per_episode(path: &Path, title: &str, episodes: &[EpisodeRecord]) -> Result<()> {
    render(path, |root| {
        let (y0, y1) = padded_range(episodes.iter().map(|e| e.distance_m).chain([0.0]));
        let n = episodes.len().max(1) as f64;
        let mut chart = new_chart(root, title, -0.5..n - 0.5, y0..y1)?;
        chart
            .configure_mesh()
            .x_desc("episode (seed order)")
            .y_desc("distance along x (m)")
            .x_label_formatter(&|x: &f64| {
                if (x - x.round()).abs() < 1e-6 {
                    format!("{x:.0}")
                } else {
                    String::new()
                }
            })
            .y_label_formatter(&|y: &f64| format!("{y:.2}"))
            .label_style((FONT, 15))
            .draw()
            .map_err(plot_error)?;
        let bar = |i: usize, e: &EpisodeRecord, ok: bool| {
            let colour = if ok { COLOURS[0] } else { COLOURS[3] };
            Rectangle::new(
                [(i as f64 - 0.35, 0.0), (i as f64 + 0.35, e.distance_m)],
                colour.filled(),
            )
        };
        chart
            .draw_series(
                episodes
                    .iter()
                    .enumerate()
                    .filter(|(_, e)| e.succeeded())
                    .map(|(i, e)| bar(i, e, true)),
            )
            .map_err(plot_error)?
            .label("ran every phase")
            .legend(|(x, y)| Rectangle::new([(x, y - 5), (x + 14, y + 5)], COLOURS[0].filled()));
        chart
            .draw_series(
                episodes
                    .iter()
                    .enumerate()
                    .filter(|(_, e)| !e.succeeded())
                    .map(|(i, e)| bar(i, e, false)),
            )
            .map_err(plot_error)?
            .label("fell")
            .legend(|(x, y)| Rectangle::new([(x, y - 5), (x + 14, y + 5)], COLOURS[3].filled()));
        draw_legend(&mut chart)
    })
}

/// h_b over the phase angle, mean and a band of one standard deviation,
/// one curve per terrain type (the paper's Fig. 4).
pub fn base_height_over_phase(path: &Path, title: &str, types: &[&TerrainSummary]) -> Result<()> {
    render(path, |root| {
        let values = types.iter().flat_map(|t| {
            t.base_height_by_angle_m.iter().filter_map(|b| {
                let (m, s) = (b.mean?, b.std.unwrap_or(0.0));
                Some([100.0 * (m - s), 100.0 * (m + s)])
            })
        });
        let (y0, y1) = padded_range(values.flatten());
        let mut chart = new_chart(root, title, 0.0..360.0, y0..y1)?;
        chart
            .configure_mesh()
            .x_desc("phase angle (deg): FL swing 0-90, RR 90-180, FR 180-270, RL 270-360")
            .y_desc("base height h_b (cm)")
            .x_labels(9)
            .label_style((FONT, 15))
            .draw()
            .map_err(plot_error)?;
        for quarter in [90.0, 180.0, 270.0] {
            chart
                .draw_series(std::iter::once(PathElement::new(
                    vec![(quarter, y0), (quarter, y1)],
                    BLACK.mix(0.3),
                )))
                .map_err(plot_error)?;
        }
        for (k, t) in types.iter().enumerate() {
            let colour = COLOURS[k % COLOURS.len()];
            let points: Vec<(f64, f64, f64)> = t
                .base_height_by_angle_m
                .iter()
                .enumerate()
                .filter_map(|(bin, b)| {
                    Some((
                        angle_bin_centre_deg(bin),
                        100.0 * b.mean?,
                        100.0 * b.std.unwrap_or(0.0),
                    ))
                })
                .collect();
            let band: Vec<(f64, f64)> = points
                .iter()
                .map(|&(x, m, s)| (x, m + s))
                .chain(points.iter().rev().map(|&(x, m, s)| (x, m - s)))
                .collect();
            chart
                .draw_series(std::iter::once(Polygon::new(band, colour.mix(0.18))))
                .map_err(plot_error)?;
            chart
                .draw_series(LineSeries::new(
                    points.iter().map(|&(x, m, _)| (x, m)),
                    colour.stroke_width(2),
                ))
                .map_err(plot_error)?
                .label(t.terrain.clone())
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 20, y)], colour.stroke_width(2))
                });
        }
        draw_legend(&mut chart)
    })
}

/// The target landing height relative to the squat per swing foot, mean
/// and one standard deviation, one colour per terrain type (Table I's foot
/// rows).
pub fn landing_height_per_foot(path: &Path, title: &str, types: &[&TerrainSummary]) -> Result<()> {
    const FEET: [&str; 4] = ["FR", "FL", "RR", "RL"];
    render(path, |root| {
        let values = types.iter().flat_map(|t| {
            t.landing_height_m.values().filter_map(|f| {
                let (m, s) = (f.mean?, f.std.unwrap_or(0.0));
                Some([100.0 * (m - s), 100.0 * (m + s)])
            })
        });
        let (y0, y1) = padded_range(values.flatten().chain([0.0]));
        let mut chart = new_chart(root, title, -0.5..3.5, y0..y1)?;
        chart
            .configure_mesh()
            .x_desc("swing foot")
            .y_desc("target landing height - squat height (cm)")
            .x_labels(9)
            .x_label_formatter(&|x: &f64| {
                let k = x.round();
                if (x - k).abs() < 1e-6 && (0.0..=3.0).contains(&k) {
                    FEET[k as usize].to_string()
                } else {
                    String::new()
                }
            })
            .label_style((FONT, 15))
            .draw()
            .map_err(plot_error)?;
        let spacing = 0.5 / types.len().max(1) as f64;
        for (k, t) in types.iter().enumerate() {
            let colour = COLOURS[k % COLOURS.len()];
            let offset = (k as f64 - (types.len() as f64 - 1.0) / 2.0) * spacing;
            let bars: Vec<_> = FEET
                .iter()
                .enumerate()
                .filter_map(|(i, foot)| {
                    let f = t.landing_height_m.get(*foot)?;
                    let (m, s) = (100.0 * f.mean?, 100.0 * f.std.unwrap_or(0.0));
                    Some(ErrorBar::new_vertical(
                        i as f64 + offset,
                        m - s,
                        m,
                        m + s,
                        colour.filled().stroke_width(2),
                        12,
                    ))
                })
                .collect();
            chart
                .draw_series(bars)
                .map_err(plot_error)?
                .label(t.terrain.clone())
                .legend(move |(x, y)| Circle::new((x + 8, y), 5, colour.filled()));
        }
        draw_legend(&mut chart)
    })
}

/// One line of a [`Panel`].
pub struct Curve {
    /// its legend entry
    pub label: String,
    /// its colour (lines of one index share a colour)
    pub colour_index: usize,
    /// (x, y) in order of x
    pub points: Vec<(f64, f64)>,
}

/// One chart of [`panels`].
pub struct Panel<'a> {
    /// its caption
    pub title: &'a str,
    /// the x axis' label
    pub x_desc: &'a str,
    /// the y axis' label
    pub y_desc: &'a str,
    /// its lines
    pub lines: &'a [Curve],
}

/// Charts of lines side by side in one figure, on one y range (each
/// chart its own x range), so that their heights compare at a glance.
pub fn panels(path: &Path, panels: &[Panel]) -> Result<()> {
    let (y0, y1) = padded_range(
        panels
            .iter()
            .flat_map(|p| p.lines.iter().flat_map(|c| c.points.iter()))
            .map(|p| p.1),
    );
    render(path, |root| {
        let areas = root.split_evenly((1, panels.len().max(1)));
        for (area, panel) in areas.iter().zip(panels) {
            let all = || panel.lines.iter().flat_map(|c| c.points.iter());
            let (x0, x1) = padded_range(all().map(|p| p.0));
            let mut chart = new_chart(area, panel.title, x0..x1, y0..y1)?;
            chart
                .configure_mesh()
                .x_desc(panel.x_desc)
                .y_desc(panel.y_desc)
                .x_label_formatter(&|x: &f64| tick_label(*x))
                .y_label_formatter(&|y: &f64| tick_label(*y))
                .label_style((FONT, 15))
                .draw()
                .map_err(plot_error)?;
            for line in panel.lines {
                let colour = COLOURS[line.colour_index % COLOURS.len()];
                chart
                    .draw_series(LineSeries::new(
                        line.points.iter().copied(),
                        colour.stroke_width(2),
                    ))
                    .map_err(plot_error)?
                    .label(line.label.clone())
                    .legend(move |(x, y)| {
                        PathElement::new(vec![(x, y), (x + 20, y)], colour.stroke_width(2))
                    });
            }
            draw_legend(&mut chart)?;
        }
        Ok(())
    })
}

#[cfg(test)]
mod tests {
    use super::tick_label;

    #[test]
    fn tick_labels_group_thousands_and_drop_trailing_zeros() {
        assert_eq!(tick_label(100_000.0), "100,000");
        assert_eq!(tick_label(1_234_567.0), "1,234,567");
        assert_eq!(tick_label(999.0), "999");
        assert_eq!(tick_label(0.0), "0");
        assert_eq!(tick_label(-2500.0), "-2,500");
        assert_eq!(tick_label(0.5), "0.5");
        assert_eq!(tick_label(1.25), "1.25");
        assert_eq!(tick_label(-0.001), "0");
        assert_eq!(tick_label(1.23456), "1.23");
    }
}
