//! The timing sweep: flight quality against each chain's predicted
//! reaction and freshness.

use super::canvas::*;

/// One chain's row of [`sweep_chart`]: its label, its spec limits
/// (reaction, freshness, ms) and its points.
pub type SweepRow = (String, (Option<f64>, Option<f64>), Vec<SweepDot>);

/// One sweep point for [`sweep_chart`]: the chain's predicted sound reaction
/// (ms), the worst roll/pitch step's tracked settling (s, capped at the
/// hold), whether the flight met the criterion, and whether the point came
/// from the delay sweep (else the period-scale sweep).
pub struct SweepDot {
    pub reaction_ms: f64,
    pub freshness_ms: f64,
    pub settling_s: f64,
    pub flies: bool,
    pub delay: bool,
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

/// The sweep's points at (`x_of`, settling capped at 1 s), one series per
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
        let pts: Vec<&SweepDot> = dots.iter().filter(|d| d.delay == delay).collect();
        if pts.is_empty() {
            continue;
        }
        chart
            .draw_series(pts.iter().map(|d| {
                let style = if d.flies {
                    color.filled()
                } else {
                    color.stroke_width(2)
                };
                Circle::new((x_of(d), d.settling_s.min(1.0)), 5, style)
            }))
            .map_err(err)?
            .label(format!("{label} (filled: flies)"))
            .legend(move |(x, y)| Circle::new((x + 8, y), 4, color.filled()));
    }
    Ok(())
}
