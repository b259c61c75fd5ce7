//! What every chart shares: the SVG canvas on white, the font, the
//! colours, text styles and number labels, the drawing-area and chart types.

pub use plotters::coord::types::RangedCoordf64;
pub use plotters::element::DashedPathElement;
pub use plotters::prelude::*;
pub use plotters::style::text_anchor::{HPos, Pos, VPos};
use rtpipe_model::Spec;

pub type Res<T> = Result<T, String>;

pub fn err<E: std::fmt::Display>(e: E) -> String {
    e.to_string()
}

pub const FONT: &str = "sans-serif";
pub const MEAN: RGBColor = RGBColor(158, 202, 225);
pub const MAX: RGBColor = RGBColor(33, 113, 181);
pub const P99: RGBColor = RGBColor(8, 48, 107);
pub const PAPER: RGBColor = RGBColor(230, 126, 0);
pub const SOUND: RGBColor = RGBColor(203, 24, 29);
pub const GREY: RGBColor = RGBColor(110, 110, 110);
pub const RELEASE: RGBColor = RGBColor(95, 95, 95);

/// Tableau 10: distinct colours for tasks.
pub const PALETTE: [RGBColor; 10] = [
    RGBColor(78, 121, 167),
    RGBColor(242, 142, 43),
    RGBColor(225, 87, 89),
    RGBColor(118, 183, 178),
    RGBColor(89, 161, 79),
    RGBColor(237, 201, 72),
    RGBColor(176, 122, 161),
    RGBColor(255, 157, 167),
    RGBColor(156, 117, 95),
    RGBColor(186, 176, 172),
];

pub fn text_style(size: u32, color: RGBColor, h: HPos, v: VPos) -> TextStyle<'static> {
    TextStyle {
        font: (FONT, size).into_font(),
        color: color.to_backend_color(),
        pos: Pos::new(h, v),
    }
}

pub fn unit_of(spec: &Spec) -> f64 {
    spec.time_unit.nanos() as f64
}

/// A short number for labels: 3 significant figures, no trailing zeros.
pub fn short(x: f64) -> String {
    let s = if x.abs() >= 100.0 {
        format!("{x:.1}")
    } else if x.abs() >= 10.0 {
        format!("{x:.2}")
    } else {
        format!("{x:.3}")
    };
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

pub type Area<DB> = DrawingArea<DB, plotters::coord::Shift>;

/// Rough width of a text in pixels (sans-serif).
pub fn text_px(s: &str, size: u32) -> i32 {
    (s.chars().count() as f64 * size as f64 * 0.46).round() as i32
}

/// A chart with `f64` axes, as every figure here draws.
pub type Chart<'a, DB> = ChartContext<'a, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>;

/// An SVG of `size` pixels on white, drawn by `draw` and returned as text.
pub fn svg(size: (u32, u32), draw: impl FnOnce(&Area<SVGBackend<'_>>) -> Res<()>) -> Res<String> {
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, size).into_drawing_area();
        root.fill(&WHITE).map_err(err)?;
        draw(&root)?;
        root.present().map_err(err)?;
    }
    Ok(svg)
}

/// How a legend entry shows its series: a line (dashed as the series is),
/// a dot (filled or hollow), a cross or a triangle.
#[derive(Clone, Copy)]
pub enum Mark {
    Line {
        color: RGBColor,
        width: u32,
        dashed: bool,
    },
    Dot {
        color: RGBColor,
        filled: bool,
    },
    Cross(RGBColor),
    Triangle(RGBColor),
    /// No swatch: a line of text, a note about the plot.
    Note,
}

/// Dash and gap of every dashed line, px: the series and its legend swatch
/// draw the same pattern.
pub const DASH: (u32, u32) = (6, 4);

/// The width of the legend column [`with_side_legend`] keeps, px.
pub const LEGEND_W: u32 = 190;

/// Splits `area` into a plot area and a legend column on its right, and
/// draws `entries` in the column: a legend outside the plot covers no
/// data. Returns the plot area.
pub fn with_side_legend<DB: DrawingBackend>(
    area: &Area<DB>,
    entries: &[(String, Mark)],
) -> Res<Area<DB>>
where
    DB::ErrorType: 'static,
{
    let (w, _) = area.dim_in_pixel();
    let (plot, legend) = area.split_horizontally(w.saturating_sub(LEGEND_W));
    for (k, (label, mark)) in entries.iter().enumerate() {
        let y = 40 + 20 * k as i32;
        draw_mark(&legend, (6, y), *mark)?;
        legend
            .draw(&Text::new(
                label.clone(),
                (38, y),
                text_style(12, BLACK, HPos::Left, VPos::Center),
            ))
            .map_err(err)?;
    }
    Ok(plot)
}

/// A legend swatch 26 px wide starting at `(x, y)`.
fn draw_mark<DB: DrawingBackend>(area: &Area<DB>, (x, y): (i32, i32), mark: Mark) -> Res<()>
where
    DB::ErrorType: 'static,
{
    let mid = (x + 13, y);
    match mark {
        Mark::Line {
            color,
            width,
            dashed: true,
        } => area.draw(&DashedPathElement::new(
            [(x, y), (x + 26, y)],
            DASH.0,
            DASH.1,
            color.stroke_width(width),
        )),
        Mark::Line { color, width, .. } => area.draw(&PathElement::new(
            [(x, y), (x + 26, y)],
            color.stroke_width(width),
        )),
        Mark::Dot { color, filled } => {
            let style = if filled {
                color.filled()
            } else {
                color.stroke_width(2)
            };
            area.draw(&Circle::new(mid, 5, style))
        }
        Mark::Cross(color) => area.draw(&Cross::new(mid, 5, color.stroke_width(2))),
        Mark::Triangle(color) => area.draw(&TriangleMarker::new(mid, 5, color.filled())),
        Mark::Note => Ok(()),
    }
    .map_err(err)
}
