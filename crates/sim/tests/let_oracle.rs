//! LET communication in the simulator against the analysis' LET figures
//! (`rtpipe_analysis::let_bound`): thousands of random LET systems and
//! phasings. LET's data flow depends on the periods and offsets alone, so
//! the simulator (event by event, whatever the schedule and the execution
//! times) must measure exactly the job-level figure of its offsets, never
//! above the arbitrary-phasing bound; with synchronous release the sound
//! bound of `analyze` under known offsets is hit exactly, and the
//! all-paths figures of a LET system are the chain's.

use rtpipe_analysis::let_bound::{any_phasing, exact, LetLatencies, LetTask};
use rtpipe_analysis::{analyze, Anchor, Metric};
use rtpipe_model::{Nanos, Spec};
use rtpipe_sim::{simulate, ExecModel, Phasing, SimConfig};

const MS: Nanos = 1_000_000;

/// Seeded draws per case (the workspace's generator) and the picks this test makes.
struct Gen(rtpipe_model::gen::Rng);

impl Gen {
    fn next(&mut self) -> u64 {
        self.0.next_u64()
    }
    fn pick<T: Copy>(&mut self, v: &[T]) -> T {
        v[(self.next() % v.len() as u64) as usize]
    }
}

/// A chain of 1–4 tasks (periods in ms) on one or two CPUs, light enough
/// that every job completes within its period (LET's premise), plus one
/// task off the chain.
fn system(g: &mut Gen, synchronous: bool) -> (Spec, Vec<Nanos>) {
    let n = 1 + (g.next() % 4) as usize;
    let periods: Vec<Nanos> = (0..n)
        .map(|_| g.pick(&[2, 3, 4, 5, 6, 8, 10, 12]))
        .collect();
    let mut src = format!(
        "[system]\nname = \"let\"\ntime_unit = \"ms\"\ncommunication = \"let\"\n{}\n[channels.mem]\nbandwidth = 100\noverhead = 0.01\n",
        if synchronous { "release = \"synchronous\"" } else { "" }
    );
    for (i, &t) in periods.iter().enumerate() {
        let server = g.pick(&["main", "none"]);
        let exec = g.pick(&[0.05, 0.1, 0.2, 0.3]);
        let cpu = g.next() % 2;
        src.push_str(&format!(
            "[tasks.t{i}]\nexec = {exec}\nexec_min = 0.01\nperiod = {t}\nserver = \"{server}\"\ncpu = {cpu}\noutput = {{ channel = \"mem\", size = 1 }}\n"
        ));
        if i > 0 {
            src.push_str(&format!("reads = [\"t{}\"]\n", i - 1));
        }
    }
    src.push_str("[tasks.other]\nexec = 0.2\nperiod = 7\ncpu = 0\n");
    let path: Vec<String> = (0..n).map(|i| format!("\"t{i}\"")).collect();
    src.push_str(&format!(
        "[[chain]]\nname = \"c\"\npath = [{}]\n",
        path.join(", ")
    ));
    let spec = Spec::parse("let.toml", &src).unwrap_or_else(|e| panic!("{e}\n{src}"));
    (spec, periods.iter().map(|&t| t * MS).collect())
}

fn observed(spec: &Spec, phasing: Phasing, horizon: Nanos, seed: u64) -> (LetLatencies, u64) {
    let cfg = SimConfig {
        horizon,
        seed,
        phasing,
        exec: ExecModel::Uniform,
        log_jobs: false,
        jitter: rtpipe_sim::Jitter::None,
    };
    let r = simulate(spec, &cfg).unwrap_or_else(|e| panic!("{e}"));
    let c = &r.chains[0];
    let get = |o: &rtpipe_joblog::Observed| o.max.unwrap_or_else(|| panic!("no observation"));
    let late: u64 = r.tasks.iter().map(|t| t.late).sum();
    (
        LetLatencies {
            reaction_read: get(&c.reaction),
            freshness_read: get(&c.freshness),
            reaction_event: get(&c.event_reaction),
            freshness_event: get(&c.event_freshness),
        },
        late,
    )
}

fn fields(l: &LetLatencies) -> [Nanos; 4] {
    [
        l.reaction_read,
        l.freshness_read,
        l.reaction_event,
        l.freshness_event,
    ]
}

#[test]
fn simulator_measures_exactly_the_let_figures() {
    let cases = 4_000;
    let (mut hit_any, mut worst_ratio, mut reached) = (0, 0.0f64, 0);
    for case in 0..cases {
        let mut g = Gen(rtpipe_model::gen::Rng::new(case as u64 + 1));
        let synchronous = case % 2 == 0;
        let (spec, periods) = system(&mut g, synchronous);
        let offsets: Vec<Nanos> = if synchronous {
            vec![0; periods.len()]
        } else {
            periods
                .iter()
                .map(|&t| (g.next() % t as u64) as Nanos)
                .collect()
        };
        let chain: Vec<LetTask> = periods
            .iter()
            .zip(&offsets)
            .map(|(&t, &phi)| LetTask { t, phi })
            .collect();
        let Ok((want, _)) = exact(&chain, 1_000_000) else {
            continue; // no sample reaches the tail with these offsets
        };
        let h = periods
            .iter()
            .fold(1, |h, &t| h / rtpipe_model::gcd(h, t) * t);
        let horizon =
            offsets.iter().max().unwrap_or(&0) + 3 * h + 6 * periods.iter().sum::<Nanos>();
        let mut given = offsets.clone();
        given.push(0); // the task off the chain
        let (got, late) = observed(&spec, Phasing::Given(given), horizon, case as u64);
        assert_eq!(late, 0, "case {case}: a job missed its LET period");
        assert_eq!(
            got, want,
            "case {case}: periods {periods:?} offsets {offsets:?}"
        );
        let any = any_phasing(&periods).unwrap_or_else(|| panic!("empty chain"));
        for (o, b) in fields(&got).iter().zip(fields(&any)) {
            assert!(*o <= b, "case {case}: {got:?} above {any:?}");
            if periods.len() > 1 {
                worst_ratio = worst_ratio.max(*o as f64 / b as f64);
                reached += usize::from(*o == b);
            }
        }
        // analyze: the sound bound is the arbitrary-phasing one; under
        // synchronous release its known-offsets figure is the exact one.
        let report = analyze(&spec);
        let sound = |m: Metric, a: Anchor| {
            report
                .chains
                .iter()
                .find(|c| c.metric == m)
                .and_then(|c| c.bound.sound(a))
        };
        assert_eq!(
            sound(Metric::Reaction, Anchor::Read),
            Some(any.reaction_read)
        );
        assert_eq!(
            sound(Metric::Freshness, Anchor::Event),
            Some(any.freshness_event)
        );
        // --all-paths: the one path from t0 to the tail has the same figures.
        let paths = rtpipe_analysis::all_paths(&spec, &report.timing);
        let pair = paths
            .pairs
            .iter()
            .find(|p| p.source == 0)
            .unwrap_or_else(|| panic!("no pair"));
        assert_eq!(
            pair.reaction_sound.value,
            Some(any.reaction_read),
            "case {case}"
        );
        assert_eq!(
            pair.freshness_sound.value,
            Some(any.freshness_read),
            "case {case}"
        );
        assert_eq!(
            pair.freshness_sound.path,
            (0..periods.len()).collect::<Vec<_>>()
        );
        if synchronous {
            let off = report.offsets[0]
                .as_ref()
                .unwrap_or_else(|| panic!("no offsets"));
            assert_eq!(
                off.get(Metric::Reaction, Anchor::Read).value,
                Some(want.reaction_read)
            );
            assert_eq!(
                off.get(Metric::Freshness, Anchor::Event).value,
                Some(want.freshness_event)
            );
            hit_any += 1;
        }
    }
    eprintln!("LET: {cases} cases, {hit_any} synchronous hit exactly; chains of 2+ tasks: largest observed / any-phasing bound {worst_ratio:.4}, {reached} figures at the bound");
    assert!(hit_any >= cases / 3);
}

/// The job log under LET holds the communication instants (read at the
/// release, publish at release + T), so the replay of the log (`run`'s
/// measurement, the `--samples` CSV) measures what the simulator measured.
#[test]
fn the_job_log_holds_the_let_instants() {
    let text = include_str!("../../../examples/let.toml");
    let spec = Spec::parse("let.toml", text).unwrap_or_else(|e| panic!("{e}"));
    for seed in 0..4 {
        let cfg = SimConfig {
            seed,
            phasing: Phasing::Sync,
            exec: ExecModel::Uniform,
            log_jobs: true,
            jitter: rtpipe_sim::Jitter::None,
            ..SimConfig::new(400 * MS)
        };
        let r = simulate(&spec, &cfg).unwrap_or_else(|e| panic!("{e}"));
        assert!(!r.jobs.is_empty());
        for j in &r.jobs {
            let t = spec.tasks[j.task].fixed_period().unwrap_or(0);
            assert_eq!((j.read, j.finish), (j.release, j.release + t), "{j:?}");
        }
        let replayed = rtpipe_joblog::chains_from_jobs(&spec, &r.jobs);
        for (a, b) in replayed.iter().zip(&r.chains) {
            assert_eq!(a.reaction, b.reaction);
            assert_eq!(a.freshness, b.freshness);
            assert_eq!(a.event_reaction, b.event_reaction);
            assert_eq!(a.event_freshness, b.event_freshness);
        }
        // examples/let.toml by hand (docs/analysis.md): 20, 25, 30, 30.
        let c = &r.chains[0];
        assert_eq!(c.reaction.max, Some(20 * MS));
        assert_eq!(c.freshness.max, Some(25 * MS));
        assert_eq!(c.event_reaction.max, Some(30 * MS));
        assert_eq!(c.event_freshness.max, Some(30 * MS));
    }
}

/// A job that has not completed by its period's end misses its LET
/// deadline: the simulator counts it late, and `analyze` gives the chain
/// no LET bound (R > T). hi: C = 6, T = 10; lo: C = 9, T = 20 on one CPU:
/// R_lo = 9 + 6·⌈R/10⌉ → 21 → 27 > 20.
#[test]
fn a_job_missing_its_period_is_late_and_unbounded() {
    let src = "[system]\nname = \"miss\"\ntime_unit = \"ms\"\ncommunication = \"let\"\n[channels.mem]\nbandwidth = 100\noverhead = 0\n[tasks.hi]\nexec = 6\nperiod = 10\nserver = \"none\"\noutput = { channel = \"mem\", size = 1 }\n[tasks.lo]\nexec = 9\nperiod = 20\nserver = \"none\"\nreads = [\"hi\"]\n[[chain]]\nname = \"c\"\npath = [\"hi\", \"lo\"]\n";
    let spec = Spec::parse("miss.toml", src).unwrap_or_else(|e| panic!("{e}"));
    let report = analyze(&spec);
    assert!(report
        .chains
        .iter()
        .all(|c| c.bound.sound(Anchor::Read).is_none()));
    let cfg = SimConfig {
        jitter: rtpipe_sim::Jitter::None,
        ..SimConfig::new(200 * MS)
    };
    let r = simulate(&spec, &cfg).unwrap_or_else(|e| panic!("{e}"));
    assert!(r.tasks[1].late > 0, "{:?}", r.tasks[1]);
    assert_eq!(r.tasks[0].late, 0);
}
