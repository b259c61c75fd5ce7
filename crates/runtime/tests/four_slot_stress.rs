//! Stress test of the four-slot register: a writer and a reader thread
//! hammer one register; every value read must be complete (all words equal
//! to a counter, the checksum matching) and never older than the value read
//! before it. `RTPIPE_STRESS_OPS` sets the total number of operations
//! (writes + reads), 2·10^7 by default; docs/runtime.md records a 10^9 run.

use rtpipe_runtime::four_slot::register;

/// Seven copies of the counter and a checksum.
fn payload(k: u64) -> [u64; 8] {
    let mut p = [k; 8];
    p[7] = k.wrapping_mul(0x9E37_79B9_7F4A_7C15).rotate_left(17) ^ 0xA5A5;
    p
}

fn ops() -> u64 {
    std::env::var("RTPIPE_STRESS_OPS")
        .ok()
        .and_then(|s| s.parse::<f64>().ok())
        .map_or(20_000_000, |x| x as u64)
}

#[test]
fn no_torn_or_stale_reads_under_contention() {
    let total = ops();
    let per_side = total / 2;
    let (mut w, mut r) = register(payload(0));
    let writer = std::thread::spawn(move || {
        for k in 1..=per_side {
            w.write(payload(k));
        }
    });
    let mut last = 0;
    let mut changes = 0u64;
    for _ in 0..per_side {
        let v = r.read();
        let k = v[0];
        assert_eq!(v, payload(k), "torn read: {v:?}");
        assert!(k >= last, "read {k} after {last}");
        changes += u64::from(k != last);
        last = k;
    }
    assert!(writer.join().is_ok());
    assert_eq!(r.read(), payload(per_side), "the last write is visible");
    eprintln!(
        "four-slot stress: {per_side} writes and {per_side} reads ({total} operations), \
         {changes} reads saw a newer value"
    );
    // The threads really overlapped (on one core they might not).
    if std::thread::available_parallelism().map_or(1, |n| n.get()) > 1 {
        assert!(changes > 1, "the reader never saw the writer's progress");
    }
}
