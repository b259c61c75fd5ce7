//! The schedule as a Gantt chart: a row per task grouped by CPU (one per
//! work-queue thread for its tasks, `rtpipe_joblog::trace::Tracks`),
//! slices, releases and publishes.

use super::canvas::*;
use rtpipe_joblog::trace::Tracks;
use rtpipe_joblog::SimResult;
use rtpipe_model::{Nanos, Server, Spec};

/// Mixes a colour with white (t = 0: the colour, 1: white).
fn lighter(c: RGBColor, t: f64) -> RGBColor {
    let m = |x: u8| (x as f64 + (255.0 - x as f64) * t).round() as u8;
    RGBColor(m(c.0), m(c.1), m(c.2))
}

fn darker(c: RGBColor) -> RGBColor {
    let m = |x: u8| (x as f64 * 0.7).round() as u8;
    RGBColor(m(c.0), m(c.1), m(c.2))
}

/// The schedule in `window`: one row per task grouped by CPU (the tasks of
/// a work-queue thread on the thread's, each slice labelled with its task
/// where it fits), CPU slices coloured per task (background-priority
/// slices light and hatched), release ticks (a data-triggered job's joined
/// to its trigger's publish by a line) and publish markers.
pub fn gantt(spec: &Spec, res: &SimResult, window: (Nanos, Nanos)) -> Res<String> {
    let u = unit_of(spec);
    let (w0, w1) = window;
    if w1 <= w0 {
        return Err("empty window".into());
    }
    let rows = Rows::of(spec);
    let row_px = 34u32;
    let name_w = rows
        .names
        .iter()
        .map(|n| n.chars().count())
        .max()
        .unwrap_or(4) as u32;
    let label_w = 70 + 8 * name_w;
    let (w, h) = (1300u32, 130 + row_px * rows.n as u32 + 60);
    svg((w, h), |root| {
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
        legend_row(root, w as i32 / 2, 48)?;
        let (x0, x1) = (w0 as f64 / u, w1 as f64 / u);
        let mut chart = ChartBuilder::on(root)
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
        draw_cpu_bands(root, &mut chart, &rows, (x0, x1))?;
        draw_task_names(root, &chart, &rows, x0)?;
        draw_slices(spec, res, root, &chart, &rows, window)?;
        draw_releases(spec, res, root, &chart, &rows, window)?;
        draw_triggered_releases(spec, res, root, &chart, &rows, window)?;
        draw_publishes(spec, res, root, &chart, &rows, window)?;
        Ok(())
    })
}

/// Half the height of a slice, in rows: slices leave a gap between rows.
const HALF_SLICE: f64 = 0.32;

/// The rows of the Gantt chart: one per track (a task, or a work-queue
/// thread's tasks), grouped by CPU id, declaration order inside a CPU.
struct Rows {
    /// The row of each task (row 0 on top).
    of: Vec<usize>,
    /// The label of each row.
    names: Vec<String>,
    /// Whether each row is a work-queue thread's (its slices are labelled).
    shared: Vec<bool>,
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
        let tracks = Tracks::of(spec);
        let mut order: Vec<usize> = (0..tracks.tracks.len()).collect();
        order.sort_by_key(|&k| (tracks.tracks[k].cpu, tracks.tracks[k].first));
        let mut row_of_track = vec![0usize; order.len()];
        let mut names = Vec::with_capacity(order.len());
        let mut shared = Vec::with_capacity(order.len());
        let mut cpus: Vec<CpuRows> = Vec::new();
        for (r, &k) in order.iter().enumerate() {
            let track = &tracks.tracks[k];
            row_of_track[k] = r;
            names.push(track.name.clone());
            shared.push(track.thread.is_some());
            let cpu = track.cpu;
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
            of: tracks.of.iter().map(|&k| row_of_track[k]).collect(),
            names,
            shared,
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

/// Each row's name (its task's, or its thread's) left of it,
/// right-aligned against the axis.
fn draw_task_names<DB: DrawingBackend>(
    root: &Area<DB>,
    chart: &Chart<'_, DB>,
    rows: &Rows,
    x0: f64,
) -> Res<()>
where
    DB::ErrorType: 'static,
{
    for (r, name) in rows.names.iter().enumerate() {
        let (px, py) = chart.backend_coord(&(x0, rows.y(r)));
        root.draw(&Text::new(
            name.clone(),
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
        let name = &spec.tasks[s.task].name;
        if rows.shared[rows.of[s.task]] && r - l > text_px(name, 11) + 6 {
            root.draw(&Text::new(
                name.clone(),
                ((l + r) / 2, (t + b) / 2),
                text_style(11, WHITE, HPos::Center, VPos::Center),
            ))
            .map_err(err)?;
        }
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

/// A data-triggered job's release: an arrow up its row at the instant (as
/// a timer's), and a dashed line from its trigger's publish on the
/// trigger's row.
fn draw_triggered_releases<DB: DrawingBackend>(
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
        let Some(tr) = j.trigger.filter(|tr| tr.task < spec.tasks.len()) else {
            continue;
        };
        if j.release < w0 || j.release > w1 || j.task >= spec.tasks.len() {
            continue;
        }
        let x = j.release as f64 / u;
        let y = rows.y(rows.of[j.task]);
        let (px, pb) = chart.backend_coord(&(x, y - 0.5));
        let (_, pt) = chart.backend_coord(&(x, y + 0.42));
        let (_, from) = chart.backend_coord(&(x, rows.y(rows.of[tr.task]) + HALF_SLICE));
        root.draw(&DashedPathElement::new(
            vec![(px, from), (px, pt)],
            3,
            3,
            RELEASE.stroke_width(1),
        ))
        .map_err(err)?;
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
