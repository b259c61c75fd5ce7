//! A mutex with priority inheritance: a POSIX mutex created with
//! `PTHREAD_PRIO_INHERIT`. While a real-time thread waits for it, the holder
//! runs at the waiter's priority, so a low-priority holder preempted by a
//! medium-priority thread cannot delay a high-priority one for longer than
//! its own critical section (`std::sync::Mutex`, a futex without
//! inheritance, can: unbounded priority inversion). The kernel implements
//! the inheritance (PI futexes, rt_mutex), for SCHED_FIFO and SCHED_DEADLINE
//! waiters alike.

use std::cell::UnsafeCell;
use std::io;
use std::marker::PhantomData;
use std::mem::ManuallyDrop;
use std::ops::{Deref, DerefMut};

/// A value behind a priority-inheritance mutex.
pub struct PiMutex<T: ?Sized> {
    /// Boxed: a pthread mutex must not move once initialised.
    raw: Box<UnsafeCell<libc::pthread_mutex_t>>,
    data: UnsafeCell<T>,
}

// SAFETY: the mutex serialises every access to `data` (as std's Mutex).
unsafe impl<T: ?Sized + Send> Send for PiMutex<T> {}
// SAFETY: as above; `&PiMutex` only gives `&mut T` under the lock.
unsafe impl<T: ?Sized + Send> Sync for PiMutex<T> {}

/// Access to the value while the lock is held; unlocks when dropped.
///
/// Not `Send`: a POSIX mutex must be unlocked by the thread that locked
/// it. `Sync` only when `T` is (as `std::sync::MutexGuard`): a shared guard
/// hands out `&T` to every thread that holds a reference to it. Both are
/// checked at compile time; the first two examples must not compile, the
/// third must:
///
/// ```compile_fail
/// use rtpipe_runtime::pi::PiMutex;
/// let m = PiMutex::new(0u64).unwrap();
/// let g = m.lock().unwrap();
/// std::thread::scope(|s| {
///     s.spawn(move || drop(g)); // unlocking on another thread
/// });
/// ```
///
/// ```compile_fail
/// use rtpipe_runtime::pi::PiMutex;
/// use std::cell::Cell;
/// let m = PiMutex::new(Cell::new(0u64)).unwrap();
/// let g = m.lock().unwrap();
/// std::thread::scope(|s| {
///     s.spawn(|| g.set(g.get() + 1)); // a data race on the Cell
///     g.set(g.get() + 1);
/// });
/// ```
///
/// ```
/// use rtpipe_runtime::pi::PiMutex;
/// use std::sync::atomic::{AtomicU64, Ordering};
/// let m = PiMutex::new(AtomicU64::new(0)).unwrap();
/// let g = m.lock().unwrap();
/// std::thread::scope(|s| {
///     s.spawn(|| g.fetch_add(1, Ordering::SeqCst)); // Sync data: fine
/// });
/// assert_eq!(g.load(Ordering::SeqCst), 1);
/// ```
pub struct PiGuard<'a, T: ?Sized> {
    mutex: &'a PiMutex<T>,
    /// Makes the guard neither `Send` nor `Sync` by default.
    _not_send: PhantomData<*const ()>,
}

// SAFETY: sharing `&PiGuard<T>` across threads shares only `&T`, which is
// sound exactly when T: Sync; the unlock stays with the owning thread.
unsafe impl<T: ?Sized + Sync> Sync for PiGuard<'_, T> {}

fn check(r: libc::c_int) -> io::Result<()> {
    if r == 0 {
        Ok(())
    } else {
        Err(io::Error::from_raw_os_error(r))
    }
}

impl<T> PiMutex<T> {
    /// `value` behind a new priority-inheritance mutex; fails only when the
    /// C library has no PI mutexes (then nothing is allocated in the kernel).
    pub fn new(value: T) -> io::Result<PiMutex<T>> {
        // SAFETY: the attribute object is initialised before use and
        // destroyed after; the mutex is initialised in place in its box,
        // which it never leaves.
        unsafe {
            let mut attr: libc::pthread_mutexattr_t = std::mem::zeroed();
            check(libc::pthread_mutexattr_init(&mut attr))?;
            let set = check(libc::pthread_mutexattr_setprotocol(
                &mut attr,
                libc::PTHREAD_PRIO_INHERIT,
            ));
            let raw = Box::new(UnsafeCell::new(std::mem::zeroed()));
            let init = set.and_then(|()| check(libc::pthread_mutex_init(raw.get(), &attr)));
            libc::pthread_mutexattr_destroy(&mut attr);
            init?;
            Ok(PiMutex {
                raw,
                data: UnsafeCell::new(value),
            })
        }
    }

    /// The value, the mutex destroyed.
    pub fn into_inner(self) -> T {
        let me = ManuallyDrop::new(self);
        // SAFETY: `me` is never used again nor dropped: each field is moved
        // out exactly once, and the mutex (unlocked: we own it) destroyed.
        unsafe {
            libc::pthread_mutex_destroy(me.raw.get());
            drop(std::ptr::read(&me.raw));
            std::ptr::read(&me.data).into_inner()
        }
    }
}

impl<T: ?Sized> PiMutex<T> {
    /// Locks, blocking (and lending the caller's priority to the holder).
    /// Errors are the kernel's (EAGAIN, EDEADLK when this thread holds it).
    pub fn lock(&self) -> io::Result<PiGuard<'_, T>> {
        // SAFETY: the mutex was initialised by `new` and lives as long as self.
        check(unsafe { libc::pthread_mutex_lock(self.raw.get()) })?;
        Ok(PiGuard {
            mutex: self,
            _not_send: PhantomData,
        })
    }
}

impl<T: ?Sized> Drop for PiMutex<T> {
    fn drop(&mut self) {
        // SAFETY: nobody holds the lock (a guard borrows the mutex).
        unsafe { libc::pthread_mutex_destroy(self.raw.get()) };
    }
}

impl<T: ?Sized> Deref for PiGuard<'_, T> {
    type Target = T;
    fn deref(&self) -> &T {
        // SAFETY: the lock is held while the guard lives.
        unsafe { &*self.mutex.data.get() }
    }
}

impl<T: ?Sized> DerefMut for PiGuard<'_, T> {
    fn deref_mut(&mut self) -> &mut T {
        // SAFETY: the lock is held while the guard lives, and the guard is
        // borrowed mutably.
        unsafe { &mut *self.mutex.data.get() }
    }
}

impl<T: ?Sized> Drop for PiGuard<'_, T> {
    fn drop(&mut self) {
        // SAFETY: this thread locked the mutex when it made the guard.
        unsafe { libc::pthread_mutex_unlock(self.mutex.raw.get()) };
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sys;
    use std::sync::atomic::{AtomicBool, Ordering};
    use std::time::{Duration, Instant};

    #[test]
    fn excludes_and_gives_the_value_back() {
        let m = match PiMutex::new(0u64) {
            Ok(m) => m,
            Err(e) => panic!("{e}"),
        };
        std::thread::scope(|s| {
            for _ in 0..4 {
                s.spawn(|| {
                    for _ in 0..100_000 {
                        if let Ok(mut g) = m.lock() {
                            // A read-modify-write that loses updates unless
                            // the lock excludes.
                            let v = *g;
                            *g = std::hint::black_box(v) + 1;
                        }
                    }
                });
            }
        });
        assert_eq!(m.into_inner(), 400_000);
    }

    #[test]
    fn unsized_values_coerce() {
        let m: PiMutex<Vec<u8>> = PiMutex::new(vec![1]).unwrap_or_else(|e| panic!("{e}"));
        let d: &PiMutex<dyn std::fmt::Debug + Send> = &m;
        let shown = d.lock().map(|g| format!("{:?}", &*g));
        assert_eq!(shown.ok().as_deref(), Some("[1]"));
    }

    /// Busy-waits for `d` of wall time.
    fn spin_for(d: Duration) {
        let t = Instant::now();
        while t.elapsed() < d {
            std::hint::spin_loop();
        }
    }

    /// Classic inversion on one CPU: L (prio 10) holds the lock, M (20) spins
    /// for 300 ms, H (30) wants the lock. With inheritance, L runs at 30 and
    /// releases within its own 20 ms; without (PTHREAD_PRIO_NONE), H waits
    /// for M's 300 ms (measured: 264 to 319 ms).
    #[test]
    fn a_waiter_lends_its_priority_to_the_holder() {
        if !sys::is_root() {
            eprintln!("SKIPPED a_waiter_lends_its_priority_to_the_holder: SCHED_FIFO needs root");
            return;
        }
        let m = PiMutex::new(()).unwrap_or_else(|e| panic!("{e}"));
        let (held, m_runs) = (AtomicBool::new(false), AtomicBool::new(false));
        let rt = |prio: i32| {
            // The class first, then the CPU: a SCHED_OTHER thread pinned
            // behind a spinning SCHED_FIFO one would not run at all.
            sys::set_fifo(prio).unwrap_or_else(|e| panic!("{e}"));
            sys::pin_to(0).unwrap_or_else(|e| panic!("{e}"));
        };
        let wait = |flag: &AtomicBool| {
            while !flag.load(Ordering::SeqCst) {
                std::thread::sleep(Duration::from_millis(1));
            }
        };
        let waited = std::thread::scope(|s| {
            s.spawn(|| {
                rt(10);
                let g = m.lock();
                held.store(true, Ordering::SeqCst);
                // Hold the lock until M runs (this thread would otherwise
                // finish before the test, starved on CPU 0, spawns M).
                let t = Instant::now();
                while !m_runs.load(Ordering::SeqCst) && t.elapsed() < Duration::from_secs(5) {
                    std::hint::spin_loop();
                }
                spin_for(Duration::from_millis(20));
                drop(g);
            });
            wait(&held);
            s.spawn(|| {
                rt(20);
                m_runs.store(true, Ordering::SeqCst);
                spin_for(Duration::from_millis(300));
            });
            wait(&m_runs);
            let h = s.spawn(|| {
                rt(30);
                let t = Instant::now();
                drop(m.lock());
                t.elapsed()
            });
            h.join().unwrap_or_else(|_| panic!("H panicked"))
        });
        assert!(
            waited < Duration::from_millis(150),
            "H waited {waited:?}: the holder did not inherit its priority"
        );
    }
}
