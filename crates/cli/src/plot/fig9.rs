//! The paper's Fig. 9: observed mean and max against the paper and sound
//! bounds, one panel per metric, one group of bars per chain.

use super::canvas::*;
use rtpipe_analysis::Metric;
use rtpipe_model::Spec;
use rtpipe_sim::observe::ChainObs;

/// Observed mean and max bars against the paper and sound bounds, one panel
/// per metric and one group of bars per chain.
pub fn fig9(spec: &Spec, obs: &[ChainObs], subtitle: &str) -> Res<String> {
    let n_chains = spec.chains.len().max(1);
    let group_px = 190u32;
    let panel_w = 110 + group_px * n_chains as u32;
    let (w, h) = ((2 * panel_w).max(900), 560u32);
    svg((w, h), |root| {
        root.draw(&Text::new(
            format!("{}: observed vs predicted end-to-end times", spec.name),
            (w as i32 / 2, 12),
            text_style(20, BLACK, HPos::Center, VPos::Top),
        ))
        .map_err(err)?;
        root.draw(&Text::new(
            subtitle.to_string(),
            (w as i32 / 2, 38),
            text_style(13, GREY, HPos::Center, VPos::Top),
        ))
        .map_err(err)?;
        // A real run (`rtpipe run`) can exceed a sound bound when it breaks
        // the model (steal time, overruns): the key then says so.
        let over: usize = obs.iter().filter_map(|o| o.read.over_sound).sum();
        let sound = match over {
            0 => "sound bound (never exceeded)".to_string(),
            n => format!("sound bound (exceeded by {n} observations)"),
        };
        fig9_legend(root, w as i32 / 2, 68, &sound)?;
        let body = root.margin(84, 0, 0, 0);
        let panels = body.split_evenly((1, 2));
        for (area, metric) in panels.iter().zip([Metric::Reaction, Metric::Freshness]) {
            let mine: Vec<&ChainObs> = obs.iter().filter(|o| o.metric == metric).collect();
            panel(spec, root, area, metric, &mine, n_chains)?;
        }
        Ok(())
    })
}

/// The key of Fig. 9, centred on x.
fn fig9_legend<DB: DrawingBackend>(root: &Area<DB>, x: i32, y: i32, sound: &str) -> Res<()>
where
    DB::ErrorType: 'static,
{
    let items: [(&str, u8); 5] = [
        ("observed mean", 0),
        ("observed max", 1),
        ("observed p99", 2),
        ("paper bound (Eqs. 1-14)", 3),
        (sound, 4),
    ];
    let widths: Vec<i32> = items
        .iter()
        .map(|(s, _)| 30 + text_px(s, 13) + 20)
        .collect();
    let mut x = x - widths.iter().sum::<i32>() / 2;
    for ((label, kind), wd) in items.iter().zip(&widths) {
        match kind {
            0 | 1 => {
                let c = if *kind == 0 { MEAN } else { MAX };
                root.draw(&Rectangle::new([(x, y - 6), (x + 22, y + 6)], c.filled()))
                    .map_err(err)?;
            }
            2 => root
                .draw(&PathElement::new(
                    vec![(x, y), (x + 22, y)],
                    P99.stroke_width(2),
                ))
                .map_err(err)?,
            3 => root
                .draw(&DashedPathElement::new(
                    vec![(x, y), (x + 22, y)],
                    6,
                    4,
                    PAPER.stroke_width(2),
                ))
                .map_err(err)?,
            _ => root
                .draw(&PathElement::new(
                    vec![(x, y), (x + 22, y)],
                    SOUND.stroke_width(2),
                ))
                .map_err(err)?,
        }
        root.draw(&Text::new(
            label.to_string(),
            (x + 30, y),
            text_style(13, BLACK, HPos::Left, VPos::Center),
        ))
        .map_err(err)?;
        x += wd;
    }
    Ok(())
}

/// One panel of Fig. 9: for one metric, a group per chain of observed mean
/// and max bars (with the p99 as a tick on the max bar) under the chain's
/// paper and sound bounds, every bar and bound labelled with its value, the
/// chain named below its group.
fn panel<DB: DrawingBackend>(
    spec: &Spec,
    root: &Area<DB>,
    area: &Area<DB>,
    metric: Metric,
    obs: &[&ChainObs],
    n: usize,
) -> Res<()>
where
    DB::ErrorType: 'static,
{
    let u = unit_of(spec);
    let top = panel_top(obs, u);
    let mut chart = ChartBuilder::on(area)
        .caption(format!("{} time", metric.name()), (FONT, 18).into_font())
        .margin_left(10)
        .margin_right(20)
        .margin_top(5)
        .x_label_area_size(56)
        .y_label_area_size(70)
        .build_cartesian_2d(0f64..n.max(2) as f64, 0f64..top)
        .map_err(err)?;
    chart
        .configure_mesh()
        .disable_x_mesh()
        .x_labels(0)
        .y_label_formatter(&|v| short(*v))
        .y_desc(format!("{} ({})", metric.name(), spec.time_unit))
        .axis_desc_style((FONT, 15))
        .label_style((FONT, 13))
        .light_line_style(RGBColor(235, 235, 235))
        .draw()
        .map_err(err)?;
    // Groups centred when there are fewer than two.
    let shift = (n.max(2) - n) as f64 / 2.0;
    let groups: Vec<BarGroup> = obs
        .iter()
        .enumerate()
        .map(|(i, o)| BarGroup::of(o, i as f64 + shift, u))
        .collect();
    draw_groups(&mut chart, &groups, top)?;
    draw_bar_labels(root, &chart, &groups)?;
    draw_bound_labels(root, &chart, &groups)?;
    draw_chain_names(spec, root, &chart, obs, shift)
}

/// The top of a Fig. 9 panel's axis (in the spec's unit): 12 % above the
/// tallest bar or bound, so their labels fit above them.
fn panel_top(obs: &[&ChainObs], u: f64) -> f64 {
    let top = obs
        .iter()
        .flat_map(|o| {
            [
                o.read.observed.map(|s| s.max as f64),
                Some(o.read.paper as f64),
                o.read.sound.map(|s| s as f64),
            ]
        })
        .flatten()
        .fold(0.0f64, f64::max)
        / u;
    if top > 0.0 {
        top * 1.12
    } else {
        1.0
    }
}

/// One chain's group of bars in a Fig. 9 panel, in the spec's unit: the
/// group spans [x, x + 1).
struct BarGroup {
    x: f64,
    /// Observed (mean, max, p99), when there were samples.
    observed: Option<(f64, f64, f64)>,
    paper: f64,
    /// `None`: the sound analysis has no bound.
    sound: Option<f64>,
}

impl BarGroup {
    fn of(o: &ChainObs, x: f64, u: f64) -> BarGroup {
        BarGroup {
            x,
            observed: o
                .read
                .observed
                .map(|s| (s.mean / u, s.max as f64 / u, s.p99 as f64 / u)),
            paper: o.read.paper as f64 / u,
            sound: o.read.sound.map(|s| s as f64 / u),
        }
    }
}

/// The bars, the p99 ticks, the bound lines and the notes of missing
/// samples or bounds, each kind as one series, in that order.
fn draw_groups<DB: DrawingBackend>(
    chart: &mut Chart<'_, DB>,
    groups: &[BarGroup],
    top: f64,
) -> Res<()>
where
    DB::ErrorType: 'static,
{
    let bar =
        |x0: f64, x1: f64, y: f64, c: RGBColor| Rectangle::new([(x0, 0.0), (x1, y)], c.filled());
    let observed = || groups.iter().filter_map(|g| g.observed.map(|o| (g.x, o)));
    chart
        .draw_series(observed().map(|(x, (mean, _, _))| bar(x + 0.2, x + 0.48, mean, MEAN)))
        .map_err(err)?;
    chart
        .draw_series(observed().map(|(x, (_, max, _))| bar(x + 0.52, x + 0.8, max, MAX)))
        .map_err(err)?;
    chart
        .draw_series(observed().map(|(x, (_, _, p99))| {
            PathElement::new(vec![(x + 0.52, p99), (x + 0.8, p99)], P99.stroke_width(2))
        }))
        .map_err(err)?;
    chart
        .draw_series(groups.iter().map(|g| {
            DashedPathElement::new(
                vec![(g.x + 0.08, g.paper), (g.x + 0.92, g.paper)],
                6,
                4,
                PAPER.stroke_width(2),
            )
        }))
        .map_err(err)?;
    chart
        .draw_series(groups.iter().filter_map(|g| {
            let s = g.sound?;
            Some(PathElement::new(
                vec![(g.x + 0.08, s), (g.x + 0.92, s)],
                SOUND.stroke_width(2),
            ))
        }))
        .map_err(err)?;
    let mut labels = Vec::new();
    for g in groups {
        if g.observed.is_none() {
            labels.push(Text::new(
                "no samples".to_string(),
                (g.x + 0.5, top * 0.05),
                text_style(12, GREY, HPos::Center, VPos::Bottom),
            ));
        }
        if g.sound.is_none() {
            labels.push(Text::new(
                "sound: unbounded".to_string(),
                (g.x + 0.08, top * 0.97),
                text_style(11, SOUND, HPos::Left, VPos::Top),
            ));
        }
    }
    chart.draw_series(labels).map_err(err)?;
    Ok(())
}

/// Bar values inside the bar's top (clear of the bound labels above the
/// lines), or above a bar too short to hold them; on the max bar, below
/// the p99 tick when the tick is where the label would go. In root pixels,
/// after the series, so that they are drawn on top.
fn draw_bar_labels<DB: DrawingBackend>(
    root: &Area<DB>,
    chart: &Chart<'_, DB>,
    groups: &[BarGroup],
) -> Res<()>
where
    DB::ErrorType: 'static,
{
    // (x, value, colour inside the bar, p99 tick) of each bar.
    let bars = groups.iter().filter_map(|g| g.observed.map(|o| (g.x, o)));
    let bars = bars.flat_map(|(x, (mean, max, p99))| {
        [
            (x + 0.34, mean, P99, None),
            (x + 0.66, max, WHITE, Some(p99)),
        ]
    });
    for (x, v, inside, tick) in bars {
        let (px, top_px) = chart.backend_coord(&(x, v));
        let (_, base_px) = chart.backend_coord(&(x, 0.0));
        // Below the p99 tick when the tick is where the label would go.
        let below = tick
            .map(|t| chart.backend_coord(&(x, t)).1)
            .filter(|&t| t > top_px + 2 && t < top_px + 20)
            .map_or(top_px + 5, |t| t + 4);
        let label = if base_px - below >= 15 {
            Text::new(
                short(v),
                (px, below),
                text_style(11, inside, HPos::Center, VPos::Top),
            )
        } else {
            Text::new(
                short(v),
                (px, top_px - 3),
                text_style(11, P99, HPos::Center, VPos::Bottom),
            )
        };
        root.draw(&label).map_err(err)?;
    }
    Ok(())
}

/// The value of each bound line above it, on a light box over whatever is
/// behind: paper at the line's right end, sound at its left end, so that
/// the two stay apart when the bounds are close.
fn draw_bound_labels<DB: DrawingBackend>(
    root: &Area<DB>,
    chart: &Chart<'_, DB>,
    groups: &[BarGroup],
) -> Res<()>
where
    DB::ErrorType: 'static,
{
    let bounds = groups.iter().flat_map(|g| {
        let paper = (
            g.x + 0.92,
            g.paper,
            format!("paper {}", short(g.paper)),
            PAPER,
        );
        let sound = g
            .sound
            .map(|s| (g.x + 0.08, s, format!("sound {}", short(s)), SOUND));
        std::iter::once(paper).chain(sound)
    });
    for (x, v, text, c) in bounds {
        let (px, py) = chart.backend_coord(&(x, v));
        let wd = text_px(&text, 11) + 4;
        let (l, r, h) = if c == PAPER {
            (px - wd, px, HPos::Right)
        } else {
            (px, px + wd, HPos::Left)
        };
        root.draw(&Rectangle::new(
            [(l, py - 15), (r, py - 2)],
            WHITE.mix(0.85).filled(),
        ))
        .map_err(err)?;
        let tx = if c == PAPER { px - 2 } else { px + 2 };
        root.draw(&Text::new(
            text,
            (tx, py - 3),
            text_style(11, c, h, VPos::Bottom),
        ))
        .map_err(err)?;
    }
    Ok(())
}

/// Chain names (and paths, when they differ) under each group, in root
/// pixels.
fn draw_chain_names<DB: DrawingBackend>(
    spec: &Spec,
    root: &Area<DB>,
    chart: &Chart<'_, DB>,
    obs: &[&ChainObs],
    shift: f64,
) -> Res<()>
where
    DB::ErrorType: 'static,
{
    for (i, o) in obs.iter().enumerate() {
        let (px, py) = chart.backend_coord(&(i as f64 + shift + 0.5, 0.0));
        let name = spec.chain_label(o.chain);
        let path = spec.path_label(&spec.chains[o.chain].path);
        root.draw(&Text::new(
            name.clone(),
            (px, py + 10),
            text_style(14, BLACK, HPos::Center, VPos::Top),
        ))
        .map_err(err)?;
        if path != name {
            root.draw(&Text::new(
                path,
                (px, py + 30),
                text_style(11, GREY, HPos::Center, VPos::Top),
            ))
            .map_err(err)?;
        }
    }
    Ok(())
}
