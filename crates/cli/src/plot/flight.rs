//! A flight over time: attitude, position, motor commands.

use super::canvas::*;
use rtpipe_flight::math::Euler;
use rtpipe_flight::trace::TracePoint;

/// One line of a time plot.
struct Series {
    name: &'static str,
    color: RGBColor,
    dashed: bool,
    points: Vec<(f64, f64)>,
}

fn series(
    name: &'static str,
    color: RGBColor,
    dashed: bool,
    trace: &[TracePoint],
    f: impl Fn(&TracePoint) -> f64,
) -> Series {
    Series {
        name,
        color,
        dashed,
        // At most ~2,000 points a line: the plots stay small and a 2 ms
        // trace has more detail than a page shows.
        points: trace
            .iter()
            .step_by(trace.len().div_ceil(2000).max(1))
            .map(|p| (p.t_ns as f64 * 1e-9, f(p)))
            .filter(|(_, y)| y.is_finite())
            .collect(),
    }
}

/// Lines over time (s), stacked panels sharing the time axis; each panel's
/// legend in a column on its right, clear of the lines.
fn time_plot(title: &str, panels: &[(&str, Vec<Series>)]) -> Res<String> {
    let h = 260 * panels.len() as u32 + 40;
    svg((960 + LEGEND_W, h), |root| {
        let root = root.titled(title, (FONT, 20).into_font()).map_err(err)?;
        let areas = root.split_evenly((panels.len(), 1));
        for ((label, lines), area) in panels.iter().zip(areas) {
            time_panel(&area, label, lines)?;
        }
        Ok(())
    })
}

/// One panel of [`time_plot`].
fn time_panel<DB: DrawingBackend>(area: &Area<DB>, label: &str, lines: &[Series]) -> Res<()>
where
    DB::ErrorType: 'static,
{
    let pts = lines.iter().flat_map(|s| s.points.iter());
    let (t0, t1, lo, hi) = pts.fold(
        (f64::MAX, f64::MIN, f64::MAX, f64::MIN),
        |(a, b, c, d), &(t, y)| (a.min(t), b.max(t), c.min(y), d.max(y)),
    );
    if t0 > t1 {
        return Ok(());
    }
    let width = |s: &Series| if s.dashed { 1 } else { 2 };
    let entries: Vec<(String, Mark)> = lines
        .iter()
        .map(|s| {
            let mark = Mark::Line {
                color: s.color,
                width: width(s),
                dashed: s.dashed,
            };
            (s.name.to_string(), mark)
        })
        .collect();
    let plot = with_side_legend(area, &entries)?;
    let pad = ((hi - lo) * 0.08).max(1e-3);
    let mut chart = ChartBuilder::on(&plot)
        .margin(8)
        .x_label_area_size(32)
        .y_label_area_size(60)
        .build_cartesian_2d(t0..t1, (lo - pad)..(hi + pad))
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_desc("time (s)")
        .y_desc(label)
        .label_style((FONT, 12))
        .draw()
        .map_err(err)?;
    for s in lines {
        let style = s.color.stroke_width(width(s));
        let points = s.points.clone();
        let drawn = if s.dashed {
            chart.draw_series(std::iter::once(DashedPathElement::new(
                points, DASH.0, DASH.1, style,
            )))
        } else {
            chart.draw_series(std::iter::once(PathElement::new(points, style)))
        };
        drawn.map_err(err)?;
    }
    Ok(())
}

/// True roll and pitch against the set-point in use and the AHRS estimate.
pub fn flight_attitude(trace: &[TracePoint]) -> Res<String> {
    let d = f64::to_degrees;
    let axis = |name: &'static str, get: fn(&Euler) -> f64, sp: fn(&TracePoint) -> f64| {
        (
            name,
            vec![
                series("set-point", PAPER, true, trace, move |p| d(sp(p))),
                series("estimate (AHRS)", MEAN, false, trace, move |p| {
                    d(get(&p.est))
                }),
                series("true", P99, false, trace, move |p| d(get(&p.euler))),
            ],
        )
    };
    time_plot(
        "attitude against set-point",
        &[
            axis("roll (deg)", |e| e.roll, |p| p.sp.roll),
            axis("pitch (deg)", |e| e.pitch, |p| p.sp.pitch),
            (
                "yaw (deg)",
                vec![
                    series("estimate (AHRS)", MEAN, false, trace, |p| d(p.est.yaw)),
                    series("true", P99, false, trace, |p| d(p.euler.yaw)),
                ],
            ),
        ],
    )
}

/// Altitude against the mission's target, and the horizontal position.
pub fn flight_altitude(trace: &[TracePoint]) -> Res<String> {
    let target = |p: &TracePoint| p.alt_target.unwrap_or(f64::NAN);
    time_plot(
        "position",
        &[
            (
                "altitude (m)",
                vec![
                    series("target", PAPER, true, trace, target),
                    series("true", P99, false, trace, |p| p.pos.z),
                ],
            ),
            (
                "horizontal (m)",
                vec![
                    series("x", PALETTE[0], false, trace, |p| p.pos.x),
                    series("y", PALETTE[1], false, trace, |p| p.pos.y),
                ],
            ),
        ],
    )
}

/// The four motor commands as the ESCs received them.
pub fn flight_motors(trace: &[TracePoint]) -> Res<String> {
    const NAMES: [&str; 4] = ["motor 1", "motor 2", "motor 3", "motor 4"];
    let lines = (0..4)
        .map(|m| series(NAMES[m], PALETTE[m], false, trace, move |p| p.motors[m]))
        .collect();
    time_plot("motor commands", &[("command (0..1)", lines)])
}
