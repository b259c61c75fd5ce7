//! The timing sweep: flight quality against each chain's predicted
//! reaction and freshness.

use super::canvas::*;

/// One chain's row of [`sweep_chart`]: its label, its spec limits
/// (reaction, freshness, ms) and its points.
pub type SweepRow = (String, (Option<f64>, Option<f64>), Vec<SweepDot>);

/// One sweep point for [`sweep_chart`]: the chain's predicted sound reaction
/// (ms), what the flight gave, whether it met the criterion, and whether
/// the point came from the delay sweep (else the period-scale sweep), and
/// its flights passed / flown (annotated beside a point some of whose
/// flights failed).
pub struct SweepDot {
    pub reaction_ms: f64,
    pub freshness_ms: f64,
    pub outcome: DotOutcome,
    pub flies: bool,
    pub delay: bool,
    pub passed: u32,
    pub flown: u32,
    /// A check point below a written limit (`--check-step`): drawn smaller.
    pub check: bool,
}

/// What a sweep point's flight gave: the measure to plot, or why there is
/// none (drawn apart, never as a measure).
pub enum DotOutcome {
    /// Flown: the mission's [`SweepMeasure`] (capped at twice its limit).
    Measured(f64),
    /// The vehicle crashed: its figures mean nothing.
    Crashed,
    /// Not flown: the controller cannot be configured at that timing.
    NotFlown,
}

/// What the sweep plots upwards: the figure the mission's criterion
/// judges (the worst step's settling for a mission with steps, a hover
/// error for one without). The axis reaches twice the limit.
pub struct SweepMeasure {
    /// The axis label with its unit, e.g. "worst step settling (s)".
    pub axis: String,
    /// The criterion line's legend, e.g. "criterion: settling < 0.5 s".
    pub criterion: String,
    /// The criterion's limit.
    pub limit: f64,
}

/// Flight quality against each chain's predicted reaction (left) and
/// freshness (right) over a sweep, one row per chain, with the spec's limit
/// (dashed) and the criterion's limit (solid) marked. `measure` is `None`
/// for a mission with nothing to measure: its flown points are left out,
/// and the legend says so.
pub fn sweep_chart(panels: &[SweepRow], measure: Option<&SweepMeasure>) -> Res<String> {
    let h = 300 * panels.len() as u32 + 40;
    svg((1200 + 2 * LEGEND_W, h), |root| {
        let root = root
            .titled(
                "flight quality against the predicted end-to-end times (sweep)",
                (FONT, 20).into_font(),
            )
            .map_err(err)?;
        let areas = root.split_evenly((panels.len(), 2));
        for (k, area) in areas.into_iter().enumerate() {
            sweep_panel(&area, &panels[k / 2], k % 2 == 1, measure)?;
        }
        Ok(())
    })
}

/// The legend of one panel: what is drawn in it, in drawing order.
fn panel_legend(
    dots: &[SweepDot],
    limit: Option<f64>,
    measure: Option<&SweepMeasure>,
) -> Vec<(String, Mark)> {
    let mut out = Vec::new();
    match measure {
        Some(m) => out.push((
            m.criterion.clone(),
            Mark::Line {
                color: SOUND,
                width: 1,
                dashed: false,
            },
        )),
        None => {
            out.push(("flown points left out: the".to_string(), Mark::Note));
            out.push(("mission has no step or hover".to_string(), Mark::Note));
        }
    }
    if let Some(l) = limit {
        let mark = Mark::Line {
            color: PAPER,
            width: 2,
            dashed: true,
        };
        out.push((format!("spec's limit {l} ms"), mark));
    }
    let measured = |delay: bool| {
        dots.iter()
            .any(|d| d.delay == delay && matches!(d.outcome, DotOutcome::Measured(_)))
    };
    for (delay, label, color) in SERIES {
        if measure.is_some() && measured(delay) {
            let mark = Mark::Dot {
                color,
                filled: true,
            };
            out.push((format!("{label} (filled: flies)"), mark));
        }
    }
    if measure.is_some() && dots.iter().any(|d| d.check) {
        out.push(("small: a check point".to_string(), Mark::Note));
    }
    if dots
        .iter()
        .any(|d| matches!(d.outcome, DotOutcome::Crashed))
    {
        out.push(("crashed (no figure)".to_string(), Mark::Cross(SOUND)));
    }
    if dots
        .iter()
        .any(|d| matches!(d.outcome, DotOutcome::NotFlown))
    {
        let mark = Mark::Triangle(GREY);
        out.push(("not flown (configuration error)".to_string(), mark));
    }
    out
}

/// The two sweeps drawn as dots: (from the delay sweep, name, colour).
const SERIES: [(bool, &str, RGBColor); 2] = [
    (false, "period scale", MAX),
    (true, "pure delay", PALETTE[4]),
];

/// One panel of [`sweep_chart`]: a chain's points against its predicted
/// freshness (`fresh`) or reaction, the criterion's limit and the spec's
/// limit as lines, and the key in a column beside the plot.
fn sweep_panel<DB: DrawingBackend>(
    area: &Area<DB>,
    (name, limits, dots): &SweepRow,
    fresh: bool,
    measure: Option<&SweepMeasure>,
) -> Res<()>
where
    DB::ErrorType: 'static,
{
    let limit = if fresh { limits.1 } else { limits.0 };
    let x_of = |d: &SweepDot| if fresh { d.freshness_ms } else { d.reaction_ms };
    let metric = if fresh { "freshness" } else { "reaction" };
    let name = format!("{name}: {metric}");
    let plot = with_side_legend(area, &panel_legend(dots, limit, measure))?;
    let x_max = dots.iter().map(x_of).chain(limit).fold(1.0, f64::max) * 1.1;
    let top = measure.map_or(1.0, |m| 2.0 * m.limit);
    let mut chart = ChartBuilder::on(&plot)
        .margin(10)
        .caption(&name, (FONT, 15))
        .x_label_area_size(34)
        .y_label_area_size(60)
        .build_cartesian_2d(0.0..x_max, 0.0..1.05 * top)
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_desc(format!("predicted sound {metric} (ms)"))
        .y_desc(measure.map_or("(nothing to measure)", |m| m.axis.as_str()))
        .label_style((FONT, 12))
        .draw()
        .map_err(err)?;
    if let Some(m) = measure {
        chart
            .draw_series(std::iter::once(PathElement::new(
                vec![(0.0, m.limit), (x_max, m.limit)],
                SOUND.stroke_width(1),
            )))
            .map_err(err)?;
    }
    if let Some(l) = limit {
        chart
            .draw_series(std::iter::once(DashedPathElement::new(
                vec![(l, 0.0), (l, 1.05 * top)],
                DASH.0,
                DASH.1,
                PAPER.stroke_width(2),
            )))
            .map_err(err)?;
    }
    if measure.is_some() {
        draw_sweep_dots(&mut chart, dots, x_of, top)?;
    }
    draw_unflown(&mut chart, dots, x_of, top)
}

/// The sweep's flown points at (`x_of`, measure capped at `top`), one
/// series per sweep (period scale, pure delay) in its own colour, filled
/// where the vehicle flies and hollow where it fails; a point flown
/// several times that passed some but not all of them is annotated
/// "passed/flown" (its pass fraction).
fn draw_sweep_dots<DB: DrawingBackend>(
    chart: &mut Chart<'_, DB>,
    dots: &[SweepDot],
    x_of: impl Fn(&SweepDot) -> f64,
    top: f64,
) -> Res<()>
where
    DB::ErrorType: 'static,
{
    for (delay, _, color) in SERIES {
        let pts = dots
            .iter()
            .filter(|d| d.delay == delay)
            .filter_map(|d| match d.outcome {
                DotOutcome::Measured(v) => Some((d, v)),
                _ => None,
            });
        chart
            .draw_series(pts.map(|(d, v)| {
                let style = if d.flies {
                    color.filled()
                } else {
                    color.stroke_width(2)
                };
                Circle::new((x_of(d), v.min(top)), if d.check { 3 } else { 5 }, style)
            }))
            .map_err(err)?;
    }
    let partial = dots.iter().filter(|d| 0 < d.passed && d.passed < d.flown);
    chart
        .draw_series(partial.filter_map(|d| match d.outcome {
            DotOutcome::Measured(v) => Some(Text::new(
                format!("{}/{}", d.passed, d.flown),
                (x_of(d), v.min(top)),
                (FONT, 11).into_font(),
            )),
            _ => None,
        }))
        .map_err(err)?;
    Ok(())
}

/// Crashes (red crosses) and timings the controller cannot be configured
/// at (grey triangles), along the top edge: no figure to show.
fn draw_unflown<DB: DrawingBackend>(
    chart: &mut Chart<'_, DB>,
    dots: &[SweepDot],
    x_of: impl Fn(&SweepDot) -> f64,
    top: f64,
) -> Res<()>
where
    DB::ErrorType: 'static,
{
    let y = 1.03 * top;
    let of = |want: fn(&DotOutcome) -> bool| {
        dots.iter()
            .filter(move |d| want(&d.outcome))
            .map(&x_of)
            .collect::<Vec<f64>>()
    };
    let crashed = of(|o| matches!(o, DotOutcome::Crashed));
    chart
        .draw_series(
            crashed
                .iter()
                .map(|&x| Cross::new((x, y), 5, SOUND.stroke_width(2))),
        )
        .map_err(err)?;
    let unflown = of(|o| matches!(o, DotOutcome::NotFlown));
    chart
        .draw_series(
            unflown
                .iter()
                .map(|&x| TriangleMarker::new((x, y), 5, GREY.filled())),
        )
        .map_err(err)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn dot(outcome: DotOutcome) -> SweepDot {
        SweepDot {
            reaction_ms: 10.0,
            freshness_ms: 10.0,
            outcome,
            flies: false,
            delay: false,
            passed: 0,
            flown: 1,
            check: false,
        }
    }

    fn settling() -> SweepMeasure {
        SweepMeasure {
            axis: "worst step settling (s)".into(),
            criterion: "criterion: settling < 0.5 s".into(),
            limit: 0.5,
        }
    }

    fn row(o: DotOutcome) -> SweepRow {
        ("gyro path".to_string(), (Some(10.0), None), vec![dot(o)])
    }

    #[test]
    fn crashes_and_configuration_errors_are_not_drawn_as_settling() {
        let m = settling();
        let svg = sweep_chart(&[row(DotOutcome::Crashed)], Some(&m)).unwrap_or_default();
        assert!(svg.contains("crashed (no figure)"), "{svg}");
        assert!(!svg.contains("<circle"), "a crash drawn as a flown point");
        let svg = sweep_chart(&[row(DotOutcome::NotFlown)], Some(&m)).unwrap_or_default();
        assert!(svg.contains("not flown (configuration error)"));
        assert!(!svg.contains("<circle"));
        let svg = sweep_chart(&[row(DotOutcome::Measured(0.3))], Some(&m)).unwrap_or_default();
        assert!(svg.contains("<circle") && !svg.contains("crashed"));
    }

    /// A check point below a limit is drawn smaller, and the legend says
    /// so; a sweep without check points says nothing of them.
    #[test]
    fn check_points_are_named_in_the_legend() {
        let mut check = dot(DotOutcome::Measured(0.2));
        check.check = true;
        let plain = [dot(DotOutcome::Measured(0.2))];
        let note = |dots: &[SweepDot]| {
            panel_legend(dots, None, Some(&settling()))
                .iter()
                .any(|(label, _)| label == "small: a check point")
        };
        assert!(note(&[check]));
        assert!(!note(&plain));
    }

    /// A point some of whose flights failed says how many passed; one
    /// whose flights all passed or all failed is not annotated.
    #[test]
    fn a_partly_passing_point_is_annotated_with_its_pass_fraction() {
        let m = settling();
        let mut partial = dot(DotOutcome::Measured(0.3));
        (partial.passed, partial.flown) = (5, 8);
        let mut all = dot(DotOutcome::Measured(0.2));
        (all.passed, all.flown, all.flies) = (8, 8, true);
        let rows = [(
            "gyro path".to_string(),
            (Some(10.0), None),
            vec![partial, all],
        )];
        let svg = sweep_chart(&rows, Some(&m)).unwrap_or_default();
        assert!(svg.contains("5/8"), "{svg}");
        assert!(!svg.contains("8/8"), "{svg}");
    }

    #[test]
    fn a_mission_without_a_measure_leaves_its_points_out_and_says_so() {
        let svg = sweep_chart(&[row(DotOutcome::Measured(0.0))], None).unwrap_or_default();
        // No point drawn at a figure of 0 that was never measured.
        assert!(!svg.contains("<circle"), "{svg}");
        assert!(svg.contains("mission has no step or hover"), "{svg}");
    }

    #[test]
    fn legend_swatches_are_dashed_as_their_lines_and_beside_the_plot() {
        let m = settling();
        let svg = sweep_chart(&[row(DotOutcome::Measured(0.3))], Some(&m)).unwrap_or_default();
        // The spec's limit (dashed) and its swatch: both drawn in dashes,
        // i.e. as several short orange segments, none as one solid line.
        let orange = "stroke=\"#E67E00\"";
        let dashes = svg.lines().filter(|l| l.contains(orange)).count();
        assert!(dashes > 4, "{svg}");
        // The legend's text sits right of every plot area (1200 + 2·190
        // wide: each half is 790 px, its plot 600): a <text> element's
        // attributes are on the line before its content.
        let lines: Vec<&str> = svg.lines().collect();
        let mut seen = 0;
        for k in 1..lines.len() {
            if !lines[k].starts_with("spec") {
                continue;
            }
            let x: f64 = lines[k - 1]
                .split("x=\"")
                .nth(1)
                .and_then(|r| r.split('"').next())
                .and_then(|v| v.parse().ok())
                .unwrap_or(0.0);
            assert!(x % 790.0 >= 600.0, "{}", lines[k - 1]);
            // Its swatch, at the text's height, is dashed: several short
            // orange segments, not one solid line.
            let y = lines[k - 1]
                .split("y=\"")
                .nth(1)
                .and_then(|r| r.split('"').next())
                .unwrap_or("?");
            let dashes = lines
                .iter()
                .filter(|l| l.contains(orange) && l.contains(&format!(",{y} ")))
                .count();
            assert!(dashes >= 2, "{dashes} segments at y = {y}");
            seen += 1;
        }
        assert_eq!(seen, 1, "{svg}");
    }
}
