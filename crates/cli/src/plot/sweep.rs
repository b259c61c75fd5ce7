//! The timing sweep: flight quality against each chain's predicted
//! reaction and freshness.

use super::canvas::*;

/// One chain's row of [`sweep_chart`]: its label, its spec limits
/// (reaction, freshness, ms) and its points.
pub type SweepRow = (String, (Option<f64>, Option<f64>), Vec<SweepDot>);

/// One sweep point for [`sweep_chart`]: the chain's predicted sound reaction
/// (ms), what the flight gave, whether it met the criterion, and whether
/// the point came from the delay sweep (else the period-scale sweep).
pub struct SweepDot {
    pub reaction_ms: f64,
    pub freshness_ms: f64,
    pub outcome: DotOutcome,
    pub flies: bool,
    pub delay: bool,
}

/// What a sweep point's flight gave: a settling to plot, or why there is
/// none (drawn apart, never as a settling).
pub enum DotOutcome {
    /// Flown: the worst roll/pitch step's tracked settling, s (capped at
    /// the hold).
    Settling(f64),
    /// The vehicle crashed: its step figures mean nothing.
    Crashed,
    /// Not flown: the controller cannot be configured at that timing.
    NotFlown,
}

/// Flight quality against each chain's predicted reaction (left) and
/// freshness (right) over a sweep, one row per chain, with the spec's limit
/// (dashed) and the criterion's settling limit (solid) marked.
pub fn sweep_chart(panels: &[SweepRow], settling_limit: f64) -> Res<String> {
    let h = 300 * panels.len() as u32 + 40;
    svg((1200, h), |root| {
        let root = root
            .titled(
                "flight quality against the predicted end-to-end times (sweep)",
                (FONT, 20).into_font(),
            )
            .map_err(err)?;
        let areas = root.split_evenly((panels.len(), 2));
        for (k, area) in areas.into_iter().enumerate() {
            sweep_panel(&area, &panels[k / 2], k % 2 == 1, settling_limit)?;
        }
        Ok(())
    })
}

/// One panel of [`sweep_chart`]: a chain's points against its predicted
/// freshness (`fresh`) or reaction, the criterion's settling limit and the
/// spec's limit as lines, and the key.
fn sweep_panel<DB: DrawingBackend>(
    area: &Area<DB>,
    (name, limits, dots): &SweepRow,
    fresh: bool,
    settling_limit: f64,
) -> Res<()>
where
    DB::ErrorType: 'static,
{
    let limit = if fresh { limits.1 } else { limits.0 };
    let x_of = |d: &SweepDot| if fresh { d.freshness_ms } else { d.reaction_ms };
    let metric = if fresh { "freshness" } else { "reaction" };
    let name = format!("{name}: {metric}");
    // Room on the right for the legend, clear of every dot.
    let x_max = dots.iter().map(x_of).chain(limit).fold(1.0, f64::max) * 1.8;
    let mut chart = ChartBuilder::on(area)
        .margin(10)
        .caption(&name, (FONT, 15))
        .x_label_area_size(34)
        .y_label_area_size(60)
        .build_cartesian_2d(0.0..x_max, 0.0..1.05)
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_desc(format!("predicted sound {metric} (ms)"))
        .y_desc("worst step settling (s)")
        .label_style((FONT, 12))
        .draw()
        .map_err(err)?;
    chart
        .draw_series(std::iter::once(PathElement::new(
            vec![(0.0, settling_limit), (x_max, settling_limit)],
            SOUND.stroke_width(1),
        )))
        .map_err(err)?
        .label(format!("criterion: settling < {settling_limit} s"))
        .legend(|(x, y)| PathElement::new([(x, y), (x + 16, y)], SOUND.stroke_width(2)));
    if let Some(l) = limit {
        chart
            .draw_series(std::iter::once(DashedPathElement::new(
                vec![(l, 0.0), (l, 1.05)],
                6,
                4,
                PAPER.stroke_width(2),
            )))
            .map_err(err)?
            .label(format!("spec's limit {l} ms"))
            .legend(|(x, y)| PathElement::new([(x, y), (x + 16, y)], PAPER.stroke_width(2)));
    }
    draw_sweep_dots(&mut chart, dots, x_of)?;
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::LowerRight)
        .background_style(WHITE.mix(0.85))
        .border_style(GREY)
        .label_font((FONT, 12))
        .draw()
        .map_err(err)?;
    Ok(())
}

/// The sweep's flown points at (`x_of`, settling capped at 1 s), one series per
/// sweep (period scale, pure delay) in its own colour, filled where the
/// vehicle flies and hollow where it fails.
fn draw_sweep_dots<DB: DrawingBackend>(
    chart: &mut Chart<'_, DB>,
    dots: &[SweepDot],
    x_of: impl Fn(&SweepDot) -> f64,
) -> Res<()>
where
    DB::ErrorType: 'static,
{
    for (delay, label, color) in [
        (false, "period scale", MAX),
        (true, "pure delay", PALETTE[4]),
    ] {
        let pts: Vec<(&SweepDot, f64)> = dots
            .iter()
            .filter(|d| d.delay == delay)
            .filter_map(|d| match d.outcome {
                DotOutcome::Settling(s) => Some((d, s)),
                _ => None,
            })
            .collect();
        if pts.is_empty() {
            continue;
        }
        chart
            .draw_series(pts.iter().map(|&(d, s)| {
                let style = if d.flies {
                    color.filled()
                } else {
                    color.stroke_width(2)
                };
                Circle::new((x_of(d), s.min(1.0)), 5, style)
            }))
            .map_err(err)?
            .label(format!("{label} (filled: flies)"))
            .legend(move |(x, y)| Circle::new((x + 8, y), 4, color.filled()));
    }
    draw_unflown(chart, dots, x_of)
}

/// Crashes (red crosses) and timings the controller cannot be configured
/// at (grey triangles), along the top edge: no settling to show.
fn draw_unflown<DB: DrawingBackend>(
    chart: &mut Chart<'_, DB>,
    dots: &[SweepDot],
    x_of: impl Fn(&SweepDot) -> f64,
) -> Res<()>
where
    DB::ErrorType: 'static,
{
    let crashed: Vec<f64> = dots
        .iter()
        .filter(|d| matches!(d.outcome, DotOutcome::Crashed))
        .map(&x_of)
        .collect();
    if !crashed.is_empty() {
        chart
            .draw_series(
                crashed
                    .iter()
                    .map(|&x| Cross::new((x, 1.03), 5, SOUND.stroke_width(2))),
            )
            .map_err(err)?
            .label("crashed (no settling)")
            .legend(|(x, y)| Cross::new((x + 8, y), 4, SOUND.stroke_width(2)));
    }
    let unflown: Vec<f64> = dots
        .iter()
        .filter(|d| matches!(d.outcome, DotOutcome::NotFlown))
        .map(&x_of)
        .collect();
    if !unflown.is_empty() {
        chart
            .draw_series(
                unflown
                    .iter()
                    .map(|&x| TriangleMarker::new((x, 1.03), 5, GREY.filled())),
            )
            .map_err(err)?
            .label("not flown (configuration error)")
            .legend(|(x, y)| TriangleMarker::new((x + 8, y), 4, GREY.filled()));
    }
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
        }
    }

    #[test]
    fn crashes_and_configuration_errors_are_not_drawn_as_settling() {
        let row = |o| ("gyro path".to_string(), (None, None), vec![dot(o)]);
        let svg = sweep_chart(&[row(DotOutcome::Crashed)], 0.5).unwrap_or_default();
        assert!(svg.contains("crashed (no settling)"), "{svg}");
        assert!(!svg.contains("<circle"), "a crash drawn as a flown point");
        let svg = sweep_chart(&[row(DotOutcome::NotFlown)], 0.5).unwrap_or_default();
        assert!(svg.contains("not flown (configuration error)"));
        assert!(!svg.contains("<circle"));
        let svg = sweep_chart(&[row(DotOutcome::Settling(0.3))], 0.5).unwrap_or_default();
        assert!(svg.contains("<circle") && !svg.contains("crashed"));
    }
}
