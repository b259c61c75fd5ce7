//! The simulator's memory is bounded by the system, not by the simulated
//! span: a run of 100 chains ten times as long peaks at no more heap
//! (counted by this binary's global allocator, not read from RSS, so the
//! test does not depend on the machine's load or its allocator's pages).

use rtpipe_model::gen::{random_system, GenConfig};
use rtpipe_model::{Nanos, Scheduler, Spec};
use rtpipe_sim::{simulate, ExecModel, Phasing, SimConfig};
use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;

/// The system allocator, counting the bytes live now and their peak.
struct Counting;

static LIVE: AtomicUsize = AtomicUsize::new(0);
static PEAK: AtomicUsize = AtomicUsize::new(0);

// SAFETY: every call is handed to `System` unchanged; only counters move.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        let p = unsafe { System.alloc(layout) };
        if !p.is_null() {
            let live = LIVE.fetch_add(layout.size(), Ordering::Relaxed) + layout.size();
            PEAK.fetch_max(live, Ordering::Relaxed);
        }
        p
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) };
        LIVE.fetch_sub(layout.size(), Ordering::Relaxed);
    }
}

#[global_allocator]
static ALLOCATOR: Counting = Counting;

/// Runs one at a time: the counters are the process's.
static ONE_AT_A_TIME: Mutex<()> = Mutex::new(());

const MS: Nanos = 1_000_000;

/// 300 tasks on 4 CPUs with 100 chains: the many-chain case where each
/// chain's latency histograms grew with the span.
fn many_chains() -> Spec {
    random_system(
        7,
        &GenConfig {
            tasks: 300,
            cpus: 4,
            utilization: 0.6,
            scheduler: Scheduler::Rm,
            mixed_servers: true,
            chains: 100,
            ..GenConfig::default()
        },
    )
}

/// The peak heap, above what was live before, of one simulation over
/// `horizon`, and the result's event count.
fn peak_heap(spec: &Spec, horizon: Nanos) -> (usize, u64) {
    let cfg = SimConfig {
        horizon,
        seed: 3,
        phasing: Phasing::Random,
        exec: ExecModel::Uniform,
        log_jobs: false,
        jitter: rtpipe_sim::Jitter::Uniform,
    };
    let before = LIVE.load(Ordering::Relaxed);
    PEAK.store(before, Ordering::Relaxed);
    let r = match simulate(spec, &cfg) {
        Ok(r) => r,
        Err(e) => panic!("{}: {e}", spec.name),
    };
    let peak = PEAK.load(Ordering::Relaxed) - before;
    (peak, r.events)
}

#[test]
fn the_heap_does_not_grow_with_the_span() {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let spec = many_chains();
    assert_eq!(spec.chains.len(), 100);
    let (short, short_events) = peak_heap(&spec, 20_000 * MS);
    let (long, long_events) = peak_heap(&spec, 200_000 * MS);
    assert!(
        long_events >= 9 * short_events,
        "{short_events} {long_events}"
    );
    eprintln!("peak heap {short} B over 20 s, {long} B over 200 s");
    // Ten times the span may add only what rarer worst cases add: a longer
    // backlog of samples on their way, a few more coarse buckets in use
    // (measured: 3.4 MB over 20 s, 4.4 MB over 200 s; with histograms
    // exact up to 65,536 values, 4.8 MB and 51 MB).
    assert!(
        long <= short + short / 2,
        "peak heap {short} B over 20 s, {long} B over 200 s ({short_events} and {long_events} events)"
    );
    // And the bound itself is the system's: four bounded histograms per
    // chain, plus the engine's per-task state.
    let histograms = 4 * spec.chains.len();
    let cap = rtpipe_joblog::hist::exact_cap(histograms);
    let per_histogram = rtpipe_joblog::Histogram::with_exact_cap(cap).max_heap_bytes();
    let bound = histograms * per_histogram + 64 * 1024 * spec.tasks.len();
    assert!(long <= bound, "peak heap {long} B above {bound} B");
}
