//! SVG figures of a simulated run: observed vs predicted end-to-end times
//! (the paper's Fig. 9) and a Gantt chart of the schedule.

use plotters::coord::types::RangedCoordf64;
use plotters::element::DashedPathElement;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use rtpipe_analysis::Metric;
use rtpipe_flight::loop_sim::TracePoint;
use rtpipe_flight::math::Euler;
use rtpipe_joblog::SimResult;
use rtpipe_model::{Nanos, Server, Spec};
use rtpipe_sim::observe::ChainObs;

type Res<T> = Result<T, String>;

fn err<E: std::fmt::Display>(e: E) -> String {
    e.to_string()
}

const FONT: &str = "sans-serif";
const MEAN: RGBColor = RGBColor(158, 202, 225);
const MAX: RGBColor = RGBColor(33, 113, 181);
const P99: RGBColor = RGBColor(8, 48, 107);
const PAPER: RGBColor = RGBColor(230, 126, 0);
const SOUND: RGBColor = RGBColor(203, 24, 29);
const GREY: RGBColor = RGBColor(110, 110, 110);
const RELEASE: RGBColor = RGBColor(95, 95, 95);

/// Tableau 10: distinct colours for tasks.
const PALETTE: [RGBColor; 10] = [
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

fn text_style(size: u32, color: RGBColor, h: HPos, v: VPos) -> TextStyle<'static> {
    TextStyle {
        font: (FONT, size).into_font(),
        color: color.to_backend_color(),
        pos: Pos::new(h, v),
    }
}

fn unit_of(spec: &Spec) -> f64 {
    spec.time_unit.nanos() as f64
}

/// A short number for labels: 3 significant figures, no trailing zeros.
fn short(x: f64) -> String {
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

/// Observed mean and max bars against the paper and sound bounds, one panel
/// per metric and one group of bars per chain.
pub fn fig9(spec: &Spec, obs: &[ChainObs], subtitle: &str) -> Res<String> {
    let n_chains = spec.chains.len().max(1);
    let group_px = 190u32;
    let panel_w = 110 + group_px * n_chains as u32;
    let (w, h) = ((2 * panel_w).max(900), 560u32);
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (w, h)).into_drawing_area();
        root.fill(&WHITE).map_err(err)?;
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
        fig9_legend(&root, w as i32 / 2, 68, &sound)?;
        let body = root.margin(84, 0, 0, 0);
        let panels = body.split_evenly((1, 2));
        for (area, metric) in panels.iter().zip([Metric::Reaction, Metric::Freshness]) {
            let mine: Vec<&ChainObs> = obs.iter().filter(|o| o.metric == metric).collect();
            panel(spec, &root, area, metric, &mine, n_chains)?;
        }
        root.present().map_err(err)?;
    }
    Ok(svg)
}

type Area<DB> = DrawingArea<DB, plotters::coord::Shift>;

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

/// Rough width of a text in pixels (sans-serif).
fn text_px(s: &str, size: u32) -> i32 {
    (s.chars().count() as f64 * size as f64 * 0.46).round() as i32
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

/// A chart with `f64` axes, as every figure here draws.
type Chart<'a, DB> = ChartContext<'a, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>;

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

/// Mixes a colour with white (t = 0: the colour, 1: white).
fn lighter(c: RGBColor, t: f64) -> RGBColor {
    let m = |x: u8| (x as f64 + (255.0 - x as f64) * t).round() as u8;
    RGBColor(m(c.0), m(c.1), m(c.2))
}

fn darker(c: RGBColor) -> RGBColor {
    let m = |x: u8| (x as f64 * 0.7).round() as u8;
    RGBColor(m(c.0), m(c.1), m(c.2))
}

/// The schedule in `window`: one row per task grouped by CPU, CPU slices
/// coloured per task (background-priority slices light and hatched),
/// release ticks and publish markers.
pub fn gantt(spec: &Spec, res: &SimResult, window: (Nanos, Nanos)) -> Res<String> {
    let u = unit_of(spec);
    let (w0, w1) = window;
    if w1 <= w0 {
        return Err("empty window".into());
    }
    let rows = Rows::of(spec);
    let row_px = 34u32;
    let name_w = spec
        .tasks
        .iter()
        .map(|t| t.name.chars().count())
        .max()
        .unwrap_or(4) as u32;
    let label_w = 70 + 8 * name_w;
    let (w, h) = (1300u32, 130 + row_px * rows.n as u32 + 60);
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (w, h)).into_drawing_area();
        root.fill(&WHITE).map_err(err)?;
        root.draw(&Text::new(
            format!(
                "{}: schedule from {} to {} {}",
                spec.name,
                spec.fmt_time(w0),
                spec.fmt_time(w1),
                spec.time_unit
            ),
            (w as i32 / 2, 12),
            text_style(20, BLACK, HPos::Center, VPos::Top),
        ))
        .map_err(err)?;
        legend_row(&root, w as i32 / 2, 48)?;
        let (x0, x1) = (w0 as f64 / u, w1 as f64 / u);
        let mut chart = ChartBuilder::on(&root)
            .margin_top(80)
            .margin_right(30)
            .margin_left(10)
            .x_label_area_size(50)
            .y_label_area_size(label_w)
            .build_cartesian_2d(x0..x1, 0f64..rows.n as f64)
            .map_err(err)?;
        chart
            .configure_mesh()
            .disable_y_mesh()
            .y_labels(0)
            .x_label_formatter(&|v| short(*v))
            .x_desc(format!("time ({})", spec.time_unit))
            .axis_desc_style((FONT, 15))
            .label_style((FONT, 13))
            .light_line_style(RGBColor(238, 238, 238))
            .bold_line_style(RGBColor(215, 215, 215))
            .draw()
            .map_err(err)?;
        draw_cpu_bands(&root, &mut chart, &rows, (x0, x1))?;
        draw_task_names(spec, &root, &chart, &rows, x0)?;
        draw_slices(spec, res, &root, &chart, &rows, window)?;
        draw_releases(spec, res, &root, &chart, &rows, window)?;
        draw_publishes(spec, res, &root, &chart, &rows, window)?;
        root.present().map_err(err)?;
    }
    Ok(svg)
}

/// Half the height of a slice, in rows: slices leave a gap between rows.
const HALF_SLICE: f64 = 0.32;

/// The rows of the Gantt chart: one per task, grouped by CPU id,
/// declaration order inside a CPU.
struct Rows {
    /// The row of each task (row 0 on top).
    of: Vec<usize>,
    /// The CPUs, top to bottom.
    cpus: Vec<CpuRows>,
    /// How many rows (at least one).
    n: usize,
}

/// The consecutive rows of one CPU's tasks.
struct CpuRows {
    cpu: u32,
    first: usize,
    rows: usize,
}

impl Rows {
    fn of(spec: &Spec) -> Rows {
        let mut order: Vec<usize> = (0..spec.tasks.len()).collect();
        order.sort_by_key(|&i| (spec.tasks[i].cpu, i));
        let mut of = vec![0usize; spec.tasks.len()];
        let mut cpus: Vec<CpuRows> = Vec::new();
        for (r, &i) in order.iter().enumerate() {
            of[i] = r;
            let cpu = spec.tasks[i].cpu;
            match cpus.last_mut() {
                Some(g) if g.cpu == cpu => g.rows += 1,
                _ => cpus.push(CpuRows {
                    cpu,
                    first: r,
                    rows: 1,
                }),
            }
        }
        Rows {
            of,
            cpus,
            n: order.len().max(1),
        }
    }

    /// The centre of row `r` on the chart's y axis: rows − r − 0.5 (row 0
    /// on top).
    fn y(&self, r: usize) -> f64 {
        (self.n - r) as f64 - 0.5
    }
}

/// Every other CPU's rows on a tinted band, a rule between CPUs, and each
/// CPU's name left of its rows.
fn draw_cpu_bands<DB: DrawingBackend>(
    root: &Area<DB>,
    chart: &mut Chart<'_, DB>,
    rows: &Rows,
    (x0, x1): (f64, f64),
) -> Res<()>
where
    DB::ErrorType: 'static,
{
    for (k, g) in rows.cpus.iter().enumerate() {
        let top = rows.y(g.first) + 0.5;
        let bottom = top - g.rows as f64;
        if k % 2 == 1 {
            chart
                .draw_series(std::iter::once(Rectangle::new(
                    [(x0, bottom), (x1, top)],
                    RGBColor(246, 246, 250).filled(),
                )))
                .map_err(err)?;
        }
        if k > 0 {
            chart
                .draw_series(std::iter::once(PathElement::new(
                    vec![(x0, top), (x1, top)],
                    RGBColor(160, 160, 160).stroke_width(1),
                )))
                .map_err(err)?;
        }
        let (_, py) = chart.backend_coord(&(x0, (top + bottom) / 2.0));
        root.draw(&Text::new(
            format!("cpu {}", g.cpu),
            (14, py),
            text_style(14, BLACK, HPos::Left, VPos::Center),
        ))
        .map_err(err)?;
    }
    Ok(())
}

/// Each task's name left of its row, right-aligned against the axis.
fn draw_task_names<DB: DrawingBackend>(
    spec: &Spec,
    root: &Area<DB>,
    chart: &Chart<'_, DB>,
    rows: &Rows,
    x0: f64,
) -> Res<()>
where
    DB::ErrorType: 'static,
{
    for (i, t) in spec.tasks.iter().enumerate() {
        let (px, py) = chart.backend_coord(&(x0, rows.y(rows.of[i])));
        root.draw(&Text::new(
            t.name.clone(),
            (px - 8, py),
            text_style(13, BLACK, HPos::Right, VPos::Center),
        ))
        .map_err(err)?;
    }
    Ok(())
}

/// The CPU slices within the window, in the task's colour; a slice at
/// background priority (a background task, or a server out of budget) is
/// light and hatched. Drawn in pixels, at least 2 wide, so that short jobs
/// stay visible.
fn draw_slices<DB: DrawingBackend>(
    spec: &Spec,
    res: &SimResult,
    root: &Area<DB>,
    chart: &Chart<'_, DB>,
    rows: &Rows,
    (w0, w1): (Nanos, Nanos),
) -> Res<()>
where
    DB::ErrorType: 'static,
{
    let u = unit_of(spec);
    for s in &res.segments {
        let (a, b) = (s.start.max(w0), s.end.min(w1));
        if b <= a || s.task >= spec.tasks.len() {
            continue;
        }
        let c = PALETTE[s.task % PALETTE.len()];
        let y = rows.y(rows.of[s.task]);
        let bg = s.background || spec.tasks[s.task].server == Server::Background;
        let fill = if bg { lighter(c, 0.6) } else { c };
        // In pixels, at least 2 wide so short jobs stay visible.
        let (l, t) = chart.backend_coord(&(a as f64 / u, y + HALF_SLICE));
        let (r, b) = chart.backend_coord(&(b as f64 / u, y - HALF_SLICE));
        let r = r.max(l + 2);
        root.draw(&Rectangle::new([(l, t), (r, b)], fill.filled()))
            .map_err(err)?;
        if bg {
            hatch(root, (l, t), (r, b), c)?;
        }
        root.draw(&Rectangle::new([(l, t), (r, b)], darker(c).stroke_width(1)))
            .map_err(err)?;
    }
    Ok(())
}

/// Releases: an arrow up from the bottom of the task's row at each release
/// in the window (and within the run), computed from the task's offset and
/// period.
fn draw_releases<DB: DrawingBackend>(
    spec: &Spec,
    res: &SimResult,
    root: &Area<DB>,
    chart: &Chart<'_, DB>,
    rows: &Rows,
    (w0, w1): (Nanos, Nanos),
) -> Res<()>
where
    DB::ErrorType: 'static,
{
    let u = unit_of(spec);
    for (i, t) in spec.tasks.iter().enumerate() {
        let Some(p) = t.fixed_period().filter(|&p| p > 0) else {
            continue;
        };
        let off = res.offsets.get(i).copied().unwrap_or(0);
        let mut r = if w0 > off {
            off + (w0 - off + p - 1) / p * p
        } else {
            off
        };
        let y = rows.y(rows.of[i]);
        while r <= w1 && r <= res.horizon {
            let x = r as f64 / u;
            let (px, pb) = chart.backend_coord(&(x, y - 0.5));
            let (_, pt) = chart.backend_coord(&(x, y + 0.42));
            root.draw(&PathElement::new(
                vec![(px, pb), (px, pt)],
                RELEASE.stroke_width(1),
            ))
            .map_err(err)?;
            root.draw(&Polygon::new(
                vec![(px, pt - 1), (px - 4, pt + 6), (px + 4, pt + 6)],
                RELEASE.filled(),
            ))
            .map_err(err)?;
            r += p;
        }
    }
    Ok(())
}

/// Publishes: a diamond on the top edge of the task's slices at each
/// completion in the window.
fn draw_publishes<DB: DrawingBackend>(
    spec: &Spec,
    res: &SimResult,
    root: &Area<DB>,
    chart: &Chart<'_, DB>,
    rows: &Rows,
    (w0, w1): (Nanos, Nanos),
) -> Res<()>
where
    DB::ErrorType: 'static,
{
    let u = unit_of(spec);
    for j in &res.jobs {
        if j.finish < w0 || j.finish > w1 || j.task >= spec.tasks.len() {
            continue;
        }
        let (px, py) =
            chart.backend_coord(&(j.finish as f64 / u, rows.y(rows.of[j.task]) + HALF_SLICE));
        root.draw(&Polygon::new(
            vec![(px, py - 5), (px + 4, py), (px, py + 5), (px - 4, py)],
            RGBColor(20, 20, 20).filled(),
        ))
        .map_err(err)?;
    }
    Ok(())
}

/// Diagonal hatching inside the pixel rectangle from p0 (top left) to p1
/// (bottom right).
fn hatch<DB: DrawingBackend>(
    root: &DrawingArea<DB, plotters::coord::Shift>,
    p0: (i32, i32),
    p1: (i32, i32),
    c: RGBColor,
) -> Res<()>
where
    DB::ErrorType: 'static,
{
    let (l, t, r, b) = (p0.0, p0.1, p1.0, p1.1);
    let hgt = b - t;
    let step = 6;
    // Lines of slope 1 (up and to the right) starting on the bottom edge at
    // x = a, for a from l − hgt to r.
    let mut a = l - hgt;
    while a < r {
        // Segment (a, b) → (a + hgt, t), clipped to [l, r].
        let (mut xs, mut ys) = (a, b);
        let (mut xe, mut ye) = (a + hgt, t);
        if xs < l {
            ys -= l - xs;
            xs = l;
        }
        if xe > r {
            ye += xe - r;
            xe = r;
        }
        if xe > xs {
            root.draw(&PathElement::new(
                vec![(xs, ys), (xe, ye)],
                c.stroke_width(1),
            ))
            .map_err(err)?;
        }
        a += step;
    }
    Ok(())
}

/// The Gantt chart's key, centred on x.
fn legend_row<DB: DrawingBackend>(
    root: &DrawingArea<DB, plotters::coord::Shift>,
    x: i32,
    y: i32,
) -> Res<()>
where
    DB::ErrorType: 'static,
{
    let c = PALETTE[0];
    let labels = [
        "job running",
        "background priority (background task, or server out of budget)",
        "release",
        "publish",
    ];
    let total: i32 = labels.iter().map(|l| 30 + text_px(l, 13) + 24).sum();
    let x = x - total / 2;
    let t = |s: &str, x: i32| {
        Text::new(
            s.to_string(),
            (x, y),
            text_style(13, BLACK, HPos::Left, VPos::Center),
        )
    };
    root.draw(&Rectangle::new([(x, y - 7), (x + 24, y + 7)], c.filled()))
        .map_err(err)?;
    root.draw(&t(labels[0], x + 30)).map_err(err)?;
    let x2 = x + 30 + text_px(labels[0], 13) + 24;
    root.draw(&Rectangle::new(
        [(x2, y - 7), (x2 + 24, y + 7)],
        lighter(c, 0.6).filled(),
    ))
    .map_err(err)?;
    hatch(root, (x2, y - 7), (x2 + 24, y + 7), c)?;
    root.draw(&t(labels[1], x2 + 30)).map_err(err)?;
    let x3 = x2 + 30 + text_px(labels[1], 13) + 24;
    root.draw(&PathElement::new(
        vec![(x3, y + 8), (x3, y - 6)],
        RELEASE.stroke_width(1),
    ))
    .map_err(err)?;
    root.draw(&Polygon::new(
        vec![(x3, y - 8), (x3 - 4, y - 1), (x3 + 4, y - 1)],
        RELEASE.filled(),
    ))
    .map_err(err)?;
    root.draw(&t(labels[2], x3 + 10)).map_err(err)?;
    let x4 = x3 + 10 + text_px(labels[2], 13) + 24;
    root.draw(&Polygon::new(
        vec![(x4, y - 5), (x4 + 4, y), (x4, y + 5), (x4 - 4, y)],
        RGBColor(20, 20, 20).filled(),
    ))
    .map_err(err)?;
    root.draw(&t(labels[3], x4 + 10)).map_err(err)?;
    Ok(())
}

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

/// Lines over time (s), stacked panels sharing the time axis.
fn time_plot(title: &str, panels: &[(&str, Vec<Series>)]) -> Res<String> {
    let mut svg = String::new();
    let h = 260 * panels.len() as u32 + 40;
    {
        let root = SVGBackend::with_string(&mut svg, (960, h)).into_drawing_area();
        root.fill(&WHITE).map_err(err)?;
        let root = root.titled(title, (FONT, 20).into_font()).map_err(err)?;
        let areas = root.split_evenly((panels.len(), 1));
        for ((label, lines), area) in panels.iter().zip(areas) {
            let pts = lines.iter().flat_map(|s| s.points.iter());
            let (t0, t1, lo, hi) = pts.fold(
                (f64::MAX, f64::MIN, f64::MAX, f64::MIN),
                |(a, b, c, d), &(t, y)| (a.min(t), b.max(t), c.min(y), d.max(y)),
            );
            if t0 > t1 {
                continue;
            }
            let pad = ((hi - lo) * 0.08).max(1e-3);
            let mut chart = ChartBuilder::on(&area)
                .margin(8)
                .x_label_area_size(32)
                .y_label_area_size(60)
                .build_cartesian_2d(t0..t1, (lo - pad)..(hi + pad))
                .map_err(err)?;
            chart
                .configure_mesh()
                .x_desc("time (s)")
                .y_desc(*label)
                .label_style((FONT, 12))
                .draw()
                .map_err(err)?;
            for s in lines {
                let style = s.color.stroke_width(if s.dashed { 1 } else { 2 });
                let drawn = if s.dashed {
                    chart.draw_series(std::iter::once(DashedPathElement::new(
                        s.points.clone(),
                        6,
                        4,
                        style,
                    )))
                } else {
                    chart.draw_series(std::iter::once(PathElement::new(s.points.clone(), style)))
                };
                let c = s.color;
                drawn.map_err(err)?.label(s.name).legend(move |(x, y)| {
                    PathElement::new([(x, y), (x + 16, y)], c.stroke_width(2))
                });
            }
            chart
                .configure_series_labels()
                .background_style(WHITE.mix(0.85))
                .border_style(GREY)
                .label_font((FONT, 12))
                .draw()
                .map_err(err)?;
        }
        root.present().map_err(err)?;
    }
    Ok(svg)
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
    let mut svg = String::new();
    {
        let h = 300 * panels.len() as u32 + 40;
        let root = SVGBackend::with_string(&mut svg, (1200, h)).into_drawing_area();
        root.fill(&WHITE).map_err(err)?;
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
        root.present().map_err(err)?;
    }
    Ok(svg)
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
