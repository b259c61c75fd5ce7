//! Latest-value registers for a 64-byte payload: Simpson's four-slot
//! register (rtpipe's), the `triple_buffer` crate, `Mutex<T>` and a seqlock.
//! Per implementation: an uncontended read, an uncontended write, and a read
//! while another thread writes in a tight loop. README.md ("Runtime") has
//! the table.

use criterion::{black_box, criterion_group, criterion_main, Criterion};
use rtpipe_runtime::four_slot;
use rtpipe_runtime::seqlock::SeqLock;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Duration;

type Payload = [u64; 8];

/// The two halves of a register, as the benchmark uses them.
trait Register {
    type W: Send + 'static;
    type R;
    fn make() -> (Self::W, Self::R);
    fn write(w: &mut Self::W, v: Payload);
    fn read(r: &mut Self::R) -> Payload;
}

struct FourSlot;
impl Register for FourSlot {
    type W = four_slot::Writer<Payload>;
    type R = four_slot::Reader<Payload>;
    fn make() -> (Self::W, Self::R) {
        four_slot::register([0; 8])
    }
    fn write(w: &mut Self::W, v: Payload) {
        w.write(v);
    }
    fn read(r: &mut Self::R) -> Payload {
        r.read()
    }
}

struct Triple;
impl Register for Triple {
    type W = triple_buffer::Input<Payload>;
    type R = triple_buffer::Output<Payload>;
    fn make() -> (Self::W, Self::R) {
        triple_buffer::triple_buffer(&[0; 8])
    }
    fn write(w: &mut Self::W, v: Payload) {
        w.write(v);
    }
    fn read(r: &mut Self::R) -> Payload {
        *r.read()
    }
}

struct Locked;
impl Register for Locked {
    type W = Arc<Mutex<Payload>>;
    type R = Arc<Mutex<Payload>>;
    fn make() -> (Self::W, Self::R) {
        let m = Arc::new(Mutex::new([0; 8]));
        (Arc::clone(&m), m)
    }
    fn write(w: &mut Self::W, v: Payload) {
        if let Ok(mut g) = w.lock() {
            *g = v;
        }
    }
    fn read(r: &mut Self::R) -> Payload {
        r.lock().map_or([0; 8], |g| *g)
    }
}

struct Seq;
impl Register for Seq {
    type W = Arc<SeqLock<8>>;
    type R = Arc<SeqLock<8>>;
    fn make() -> (Self::W, Self::R) {
        let l = Arc::new(SeqLock::new([0; 8]));
        (Arc::clone(&l), l)
    }
    fn write(w: &mut Self::W, v: Payload) {
        w.write(v);
    }
    fn read(r: &mut Self::R) -> Payload {
        r.read()
    }
}

fn bench<R: Register>(c: &mut Criterion, name: &str) {
    let mut g = c.benchmark_group(name);
    g.sample_size(30)
        .warm_up_time(Duration::from_millis(300))
        .measurement_time(Duration::from_secs(1));
    let (mut w, mut r) = R::make();
    g.bench_function("read", |b| b.iter(|| black_box(R::read(&mut r))));
    let mut k = 0u64;
    g.bench_function("write", |b| {
        b.iter(|| {
            k = k.wrapping_add(1);
            R::write(&mut w, black_box([k; 8]));
        })
    });
    let stop = Arc::new(AtomicBool::new(false));
    let stop2 = Arc::clone(&stop);
    let writer = std::thread::spawn(move || {
        let mut k = 0u64;
        while !stop2.load(Ordering::Relaxed) {
            k = k.wrapping_add(1);
            R::write(&mut w, [k; 8]);
        }
    });
    g.bench_function("read_contended", |b| b.iter(|| black_box(R::read(&mut r))));
    stop.store(true, Ordering::Relaxed);
    let _ = writer.join();
    g.finish();
}

fn registers(c: &mut Criterion) {
    bench::<FourSlot>(c, "four_slot");
    bench::<Triple>(c, "triple_buffer");
    bench::<Locked>(c, "mutex");
    bench::<Seq>(c, "seqlock");
}

criterion_group!(benches, registers);
criterion_main!(benches);
