//! Thin wrappers over the Linux calls the executor needs: clocks, absolute
//! sleeps, scheduling classes (including `SCHED_DEADLINE` through the raw
//! `sched_setattr` system call, which glibc does not wrap), affinity,
//! `mlockall`, and the steal time of /proc/stat.

use std::io;

/// `SCHED_DEADLINE` (include/uapi/linux/sched.h).
pub const SCHED_DEADLINE: u32 = 6;

/// `struct sched_attr` (include/uapi/linux/sched/types.h), version 0 (48 bytes).
#[repr(C)]
#[derive(Debug, Default, Clone, Copy)]
struct SchedAttr {
    size: u32,
    sched_policy: u32,
    sched_flags: u64,
    sched_nice: i32,
    sched_priority: u32,
    sched_runtime: u64,
    sched_deadline: u64,
    sched_period: u64,
}

/// CLOCK_MONOTONIC in nanoseconds.
pub fn now() -> i64 {
    clock(libc::CLOCK_MONOTONIC)
}

/// CPU time consumed by the calling thread, in nanoseconds.
pub fn thread_cpu_time() -> i64 {
    clock(libc::CLOCK_THREAD_CPUTIME_ID)
}

fn clock(id: libc::clockid_t) -> i64 {
    let mut ts = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: `ts` is a valid, writable timespec; both clocks always exist.
    unsafe { libc::clock_gettime(id, &mut ts) };
    ts.tv_sec * 1_000_000_000 + ts.tv_nsec
}

/// Sleeps until CLOCK_MONOTONIC reads `t` (absolute: no drift), resuming
/// after signals.
pub fn sleep_until(t: i64) {
    let ts = libc::timespec {
        tv_sec: t.div_euclid(1_000_000_000),
        tv_nsec: t.rem_euclid(1_000_000_000),
    };
    loop {
        // SAFETY: `ts` is a valid timespec; no remainder is asked for.
        let r = unsafe {
            libc::clock_nanosleep(
                libc::CLOCK_MONOTONIC,
                libc::TIMER_ABSTIME,
                &ts,
                std::ptr::null_mut(),
            )
        };
        if r != libc::EINTR {
            return;
        }
    }
}

/// Sleeps while `word` still holds `seen`, until CLOCK_MONOTONIC reads
/// `until` (absolute) or [`wake`] is called on it; may return early
/// (signals, spurious wake-ups): the caller re-checks what it waits for.
/// A futex, so a waiting work-queue thread costs nothing and a wake-up
/// allocates nothing.
pub fn wait_until(word: &std::sync::atomic::AtomicU32, seen: u32, until: i64) {
    let ts = libc::timespec {
        tv_sec: until.div_euclid(1_000_000_000),
        tv_nsec: until.rem_euclid(1_000_000_000),
    };
    // SAFETY: FUTEX_WAIT_BITSET on a live, aligned u32 (the atomic), with a
    // valid absolute CLOCK_MONOTONIC timespec and the match-any mask; it
    // only reads the word and sleeps.
    unsafe {
        libc::syscall(
            libc::SYS_futex,
            word.as_ptr(),
            libc::FUTEX_WAIT_BITSET | libc::FUTEX_PRIVATE_FLAG,
            seen,
            &ts as *const libc::timespec,
            std::ptr::null::<u32>(),
            libc::FUTEX_BITSET_MATCH_ANY,
        );
    }
}

/// Wakes every thread in [`wait_until`] on `word` (the caller has changed
/// the word first, so a thread about to wait sees the change and does not).
pub fn wake(word: &std::sync::atomic::AtomicU32) {
    // SAFETY: FUTEX_WAKE on a live, aligned u32; it touches no memory.
    unsafe {
        libc::syscall(
            libc::SYS_futex,
            word.as_ptr(),
            libc::FUTEX_WAKE | libc::FUTEX_PRIVATE_FLAG,
            i32::MAX,
        );
    }
}

/// `SCHED_FIFO` at `priority` (1..=99) for the calling thread.
pub fn set_fifo(priority: i32) -> io::Result<()> {
    let p = libc::sched_param {
        sched_priority: priority,
    };
    // SAFETY: `p` is a valid sched_param; pid 0 is the calling thread.
    if unsafe { libc::sched_setscheduler(0, libc::SCHED_FIFO, &p) } != 0 {
        return Err(io::Error::last_os_error());
    }
    Ok(())
}

/// Changes the calling SCHED_FIFO thread's priority, keeping its class (a
/// ceiling's raise and restore). Lowered, the thread goes to the head of
/// its new priority's queue; raised, to the tail (sched(7)).
pub fn set_priority(priority: i32) -> io::Result<()> {
    let p = libc::sched_param {
        sched_priority: priority,
    };
    // SAFETY: `p` is a valid sched_param; pid 0 is the calling thread.
    if unsafe { libc::sched_setparam(0, &p) } != 0 {
        return Err(io::Error::last_os_error());
    }
    Ok(())
}

/// Changes thread `tid`'s SCHED_FIFO priority, keeping its class (the EDF
/// dispatcher's re-ranking, `crate::edf`).
pub fn set_priority_of(tid: i32, priority: i32) -> io::Result<()> {
    let p = libc::sched_param {
        sched_priority: priority,
    };
    // SAFETY: `p` is a valid sched_param; `tid` names a thread of this
    // process (a wrong id fails with ESRCH, changing nothing).
    if unsafe { libc::sched_setparam(tid, &p) } != 0 {
        return Err(io::Error::last_os_error());
    }
    Ok(())
}

/// `sched_attr.sched_flags`: the kernel sends the thread SIGXCPU when its
/// reservation overruns its runtime (include/uapi/linux/sched.h).
pub const SCHED_FLAG_DL_OVERRUN: u64 = 0x04;

/// `SCHED_DEADLINE` with runtime, deadline and period (ns) and `flags`
/// (0 or [`SCHED_FLAG_DL_OVERRUN`]) for the calling thread.
pub fn set_deadline(runtime: u64, deadline: u64, period: u64, flags: u64) -> io::Result<()> {
    let attr = SchedAttr {
        size: std::mem::size_of::<SchedAttr>() as u32,
        sched_policy: SCHED_DEADLINE,
        sched_flags: flags,
        sched_runtime: runtime,
        sched_deadline: deadline,
        sched_period: period,
        ..SchedAttr::default()
    };
    // SAFETY: sched_setattr(pid 0 = calling thread, a valid sched_attr whose
    // size field is its size, flags 0).
    let r = unsafe { libc::syscall(libc::SYS_sched_setattr, 0, &attr as *const SchedAttr, 0u32) };
    if r != 0 {
        return Err(io::Error::last_os_error());
    }
    Ok(())
}

/// The calling thread's kernel id.
pub fn gettid() -> i32 {
    // SAFETY: gettid takes no arguments and cannot fail.
    unsafe { libc::gettid() }
}

/// Moves thread `tid` (of any class) to `SCHED_OTHER`, nice 0.
pub fn set_other(tid: i32) -> io::Result<()> {
    let attr = SchedAttr {
        size: std::mem::size_of::<SchedAttr>() as u32,
        sched_policy: libc::SCHED_OTHER as u32,
        ..SchedAttr::default()
    };
    // SAFETY: sched_setattr(tid, a valid sched_attr whose size field is its
    // size, flags 0); a stale tid only makes it fail (ESRCH).
    let r = unsafe {
        libc::syscall(
            libc::SYS_sched_setattr,
            tid,
            &attr as *const SchedAttr,
            0u32,
        )
    };
    if r != 0 {
        return Err(io::Error::last_os_error());
    }
    Ok(())
}

/// Pins the calling thread to `cpu`.
pub fn pin_to(cpu: usize) -> io::Result<()> {
    // SAFETY: a zeroed cpu_set_t is the empty set; CPU_SET stays in bounds
    // for cpu < CPU_SETSIZE (checked), and the set is passed with its size.
    unsafe {
        if cpu >= libc::CPU_SETSIZE as usize {
            return Err(io::Error::from_raw_os_error(libc::EINVAL));
        }
        let mut set: libc::cpu_set_t = std::mem::zeroed();
        libc::CPU_SET(cpu, &mut set);
        if libc::sched_setaffinity(0, std::mem::size_of::<libc::cpu_set_t>(), &set) != 0 {
            return Err(io::Error::last_os_error());
        }
    }
    Ok(())
}

/// Locks current and future memory (no page faults in the periodic path).
pub fn lock_memory() -> io::Result<()> {
    // SAFETY: mlockall takes flags only.
    if unsafe { libc::mlockall(libc::MCL_CURRENT | libc::MCL_FUTURE) } != 0 {
        return Err(io::Error::last_os_error());
    }
    Ok(())
}

/// Gives up the CPU (`SCHED_DEADLINE`: ends the job until the next period).
pub fn yield_now() {
    // SAFETY: no arguments.
    unsafe { libc::sched_yield() };
}

/// The CPUs the process may run on.
pub fn online_cpus() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get())
}

/// Steal time of all CPUs so far (the `steal` column of /proc/stat's `cpu`
/// line), in nanoseconds; `None` when unavailable.
pub fn steal_time() -> Option<i64> {
    let stat = std::fs::read_to_string("/proc/stat").ok()?;
    let line = stat.lines().find(|l| l.starts_with("cpu "))?;
    let steal: i64 = line.split_whitespace().nth(8)?.parse().ok()?;
    Some(steal * tick_ns())
}

/// One clock tick of /proc/stat (1/USER_HZ), ns.
pub fn tick_ns() -> i64 {
    // SAFETY: sysconf takes a constant.
    let hz = unsafe { libc::sysconf(libc::_SC_CLK_TCK) };
    if hz > 0 {
        1_000_000_000 / hz as i64
    } else {
        10_000_000
    }
}

static STOP: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);
/// [`now`] when the first stop signal arrived.
static STOP_AT: std::sync::atomic::AtomicI64 = std::sync::atomic::AtomicI64::new(0);
/// The first stop signal's number.
static STOP_SIGNAL: std::sync::atomic::AtomicI32 = std::sync::atomic::AtomicI32::new(0);

/// The signals that stop a command the way Ctrl-C does: SIGINT (Ctrl-C),
/// SIGTERM (`kill`, `timeout`, a service manager) and SIGHUP (the terminal
/// closed). Each ends the command through its own clean-up (a run's
/// cpusets, a `--samples` file's temporaries) rather than killing it
/// where it stands.
pub const STOP_SIGNALS: [libc::c_int; 3] = [libc::SIGINT, libc::SIGTERM, libc::SIGHUP];

extern "C" fn on_stop_signal(signal: libc::c_int) {
    use std::sync::atomic::Ordering::SeqCst;
    // clock_gettime is async-signal-safe (POSIX.1-2008, signal-safety(7)).
    // The instant and the signal are stored before the flag, so whoever
    // sees the flag sees them.
    if !STOP.load(SeqCst) {
        STOP_AT.store(now(), SeqCst);
        STOP_SIGNAL.store(signal, SeqCst);
    }
    STOP.store(true, SeqCst);
}

thread_local! {
    /// SIGXCPUs this thread received: its SCHED_DEADLINE reservation
    /// overran ([`SCHED_FLAG_DL_OVERRUN`]). Const-initialised, no
    /// destructor: a plain thread-local word, safe to touch in a handler.
    static DL_OVERRUNS: std::cell::Cell<u32> = const { std::cell::Cell::new(0) };
}

extern "C" fn on_dl_overrun(_: libc::c_int) {
    DL_OVERRUNS.with(|c| c.set(c.get().saturating_add(1)));
}

/// Installs the SIGXCPU handler that counts the calling thread's
/// reservation overruns ([`take_dl_overruns`]). It stays installed after
/// the run: the kernel signals an overrun at the thread's next tick, so
/// one may still be on its way when the run ends, and SIGXCPU's default
/// action would kill the process.
pub fn count_dl_overruns() {
    let handler: extern "C" fn(libc::c_int) = on_dl_overrun;
    // SAFETY: the handler only adds to a thread-local word.
    unsafe { libc::signal(libc::SIGXCPU, handler as libc::sighandler_t) };
}

/// The reservation overruns signalled to the calling thread since the last
/// call (see [`count_dl_overruns`]).
pub fn take_dl_overruns() -> u32 {
    DL_OVERRUNS.with(|c| c.replace(0))
}

/// Installs the handler of every [`STOP_SIGNALS`] signal: it sets the stop
/// flag ([`stop_requested`]). The one home of signal handling: every
/// command that has something to undo when stopped calls it.
pub fn catch_stop_signals() {
    STOP.store(false, std::sync::atomic::Ordering::SeqCst);
    let handler: extern "C" fn(libc::c_int) = on_stop_signal;
    for signal in STOP_SIGNALS {
        // SAFETY: the handler only reads a clock and stores to atomics
        // (async-signal-safe).
        unsafe { libc::signal(signal, handler as libc::sighandler_t) };
    }
}

/// Whether a stop signal arrived since [`catch_stop_signals`].
pub fn stop_requested() -> bool {
    STOP.load(std::sync::atomic::Ordering::SeqCst)
}

/// When the first stop signal arrived since [`catch_stop_signals`]
/// ([`now`]'s clock).
pub fn stop_instant() -> Option<i64> {
    stop_requested().then(|| STOP_AT.load(std::sync::atomic::Ordering::SeqCst))
}

/// The first stop signal since [`catch_stop_signals`], by number.
pub fn stop_signal() -> Option<libc::c_int> {
    stop_requested().then(|| STOP_SIGNAL.load(std::sync::atomic::Ordering::SeqCst))
}

/// How a message names the stop: "Ctrl-C" for SIGINT, else the signal's
/// name ("SIGTERM", "SIGHUP").
pub fn stop_name() -> &'static str {
    match stop_signal() {
        Some(libc::SIGTERM) => "SIGTERM",
        Some(libc::SIGHUP) => "SIGHUP",
        _ => "Ctrl-C",
    }
}

/// `CAP_IPC_LOCK`: lock memory beyond RLIMIT_MEMLOCK.
pub const CAP_IPC_LOCK: u32 = 14;
/// `CAP_SYS_NICE`: real-time scheduling classes and priorities.
pub const CAP_SYS_NICE: u32 = 23;

/// Whether the process holds capability `cap` in its effective set
/// (`CapEff` of /proc/self/status; false when that cannot be read).
pub fn has_capability(cap: u32) -> bool {
    let Ok(status) = std::fs::read_to_string("/proc/self/status") else {
        return false;
    };
    status
        .lines()
        .find_map(|l| l.strip_prefix("CapEff:"))
        .and_then(|hex| u64::from_str_radix(hex.trim(), 16).ok())
        .is_some_and(|set| set >> cap & 1 == 1)
}

/// The soft limit of `resource` (`u64::MAX`: unlimited).
pub fn soft_limit(resource: libc::__rlimit_resource_t) -> u64 {
    let mut r = libc::rlimit {
        rlim_cur: 0,
        rlim_max: 0,
    };
    // SAFETY: getrlimit writes the struct it is given.
    if unsafe { libc::getrlimit(resource, &mut r) } != 0 {
        return 0;
    }
    if r.rlim_cur == libc::RLIM_INFINITY {
        u64::MAX
    } else {
        r.rlim_cur
    }
}

/// Whether the process runs with an effective user id of 0.
pub fn is_root() -> bool {
    // SAFETY: geteuid cannot fail.
    unsafe { libc::geteuid() == 0 }
}
