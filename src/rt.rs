//! The thread shells' view of the system: the clock, and real-time scheduling for
//! the latency path.
//!
//! [`monotonic_now`] reads CLOCK_MONOTONIC; only thread shells (input, control loop,
//! outputs, workers) call it, the cores (`gesture`, `crowd`, `engine`) are given
//! `now`, which keeps replays deterministic.
//!
//! The input, control and publisher threads (and each client's writer) run under
//! SCHED_FIFO when the config asks for it, so a busy machine — a renderer on the
//! same box, the assignment worker, the client itself — cannot hold a touch back by
//! a scheduler time slice. Memory can be locked (`mlockall`) so the path never takes
//! a page fault. Both need privileges (RLIMIT_RTPRIO / RLIMIT_MEMLOCK, granted by the
//! shipped systemd unit, or CAP_SYS_NICE / CAP_IPC_LOCK); when the system refuses,
//! the daemon says so once and carries on at normal priority.

use crate::vocab::Micros;
use std::sync::atomic::{AtomicBool, Ordering};

static REFUSAL_LOGGED: AtomicBool = AtomicBool::new(false);
static GRANTED: AtomicBool = AtomicBool::new(false);

/// Whether any thread of this process has been made real-time.
pub fn realtime_granted() -> bool {
    GRANTED.load(Ordering::Relaxed)
}

/// Runs the calling thread under SCHED_FIFO at `priority` (1..=99). Returns whether
/// it took effect; a refusal is logged once per process.
pub fn make_realtime(priority: u8, thread: &str) -> bool {
    use thread_priority::unix::{
        set_thread_priority_and_policy, thread_native_id, RealtimeThreadSchedulePolicy,
        ThreadSchedulePolicy,
    };
    use thread_priority::{ThreadPriority, ThreadPriorityValue};
    let policy = ThreadSchedulePolicy::Realtime(RealtimeThreadSchedulePolicy::Fifo);
    let result = ThreadPriorityValue::try_from(priority.min(99))
        .map_err(|e| format!("priority {priority}: {e}"))
        .and_then(|v| {
            set_thread_priority_and_policy(
                thread_native_id(),
                ThreadPriority::Crossplatform(v),
                policy,
            )
            .map_err(|e| format!("{e:?}"))
        });
    match result {
        Ok(()) => {
            GRANTED.store(true, Ordering::Relaxed);
            true
        }
        Err(e) => {
            if !REFUSAL_LOGGED.swap(true, Ordering::Relaxed) {
                log::warn!(
                    "real-time scheduling refused for the {thread} thread ({e}); running at normal priority. \
                     Grant RLIMIT_RTPRIO (the systemd unit's LimitRTPRIO=) or set pipeline.realtime.priority: None"
                );
            }
            false
        }
    }
}

/// Nice value of the assignment worker ([`make_background`]).
pub const WORKER_NICE: i32 = 10;

/// Lowers the calling thread to nice [`WORKER_NICE`] (SCHED_OTHER): for the
/// assignment worker, so a long solve takes mostly what the latency path leaves.
/// The real-time threads (SCHED_FIFO) always preempt it. Without real-time
/// scheduling it weighs 110 against a normal thread's 1024 in the kernel's fair
/// share. Neither SCHED_IDLE nor nice 19: on a machine kept busy by something else
/// (a renderer on the same box, a parallel build) such a thread gets nearly nothing,
/// and the assignment would stop refreshing.
pub fn make_background(thread: &str) {
    use thread_priority::unix::{
        set_thread_priority_and_policy, thread_native_id, NormalThreadSchedulePolicy,
        ThreadSchedulePolicy,
    };
    use thread_priority::{ThreadPriority, ThreadPriorityValue};
    // thread-priority maps 0..=99 linearly onto nice 19..=-20 for normal policies:
    // 22 is nice 10.
    let r = ThreadPriorityValue::try_from(22u8)
        .map_err(|e| format!("{e:?}"))
        .and_then(|v| {
            set_thread_priority_and_policy(
                thread_native_id(),
                ThreadPriority::Crossplatform(v),
                ThreadSchedulePolicy::Normal(NormalThreadSchedulePolicy::Other),
            )
            .map_err(|e| format!("{e:?}"))
        });
    if let Err(e) = r {
        log::warn!(
            "could not lower the {thread} thread to nice {WORKER_NICE} ({e}); it competes with the latency path"
        );
    }
}

/// The calling thread's nice value, from `/proc/thread-self/stat` (Linux).
pub fn thread_nice() -> Option<i32> {
    let stat = std::fs::read_to_string("/proc/thread-self/stat").ok()?;
    // Fields after the parenthesised command name; nice is field 19 overall.
    let rest = &stat[stat.rfind(')')? + 2..];
    rest.split_whitespace().nth(16)?.parse().ok()
}

/// The smallest `RLIMIT_MEMLOCK` under which the daemon locks its memory (bytes).
///
/// `mlockall(MCL_FUTURE)` makes every later mapping count against the limit: a thread
/// stack, a client's buffers, a bigger crowd. Under a small limit (the kernel's default
/// is 8 MiB) those allocations would fail later, far from the cause, so the daemon
/// does not lock at all and says why. The shipped unit grants 256 MiB.
pub const MIN_MEMLOCK_BYTES: u64 = 128 << 20;

/// Locks the process's current and future memory into RAM. Returns whether it took
/// effect; a refusal is logged. Root (CAP_IPC_LOCK) is not bound by the limit; anyone
/// else needs `RLIMIT_MEMLOCK` of at least [`MIN_MEMLOCK_BYTES`].
pub fn lock_memory() -> bool {
    use nix::sys::mman::{mlockall, MlockAllFlags};
    use nix::sys::resource::{getrlimit, Resource, RLIM_INFINITY};
    if let Ok((soft, _)) = getrlimit(Resource::RLIMIT_MEMLOCK) {
        if soft != RLIM_INFINITY && soft < MIN_MEMLOCK_BYTES && !nix::unistd::geteuid().is_root() {
            log::warn!(
                "not locking memory: RLIMIT_MEMLOCK is {} KiB, under the {} MiB the daemon needs \
                 to keep allocating with its memory locked; page faults may delay frames. Grant \
                 it (the systemd unit's LimitMEMLOCK=256M) or set pipeline.realtime.lock_memory: false",
                soft / 1024,
                MIN_MEMLOCK_BYTES >> 20
            );
            return false;
        }
    }
    match mlockall(MlockAllFlags::MCL_CURRENT | MlockAllFlags::MCL_FUTURE) {
        Ok(()) => true,
        Err(e) => {
            log::warn!(
                "could not lock memory ({e}); page faults may delay frames. Grant RLIMIT_MEMLOCK \
                 (the systemd unit's LimitMEMLOCK=) or set pipeline.realtime.lock_memory: false"
            );
            false
        }
    }
}

/// Pins the calling thread to `cpus`. Returns whether it took effect; a refusal is
/// logged.
pub fn pin_to_cpus(cpus: &[usize], thread: &str) -> bool {
    use nix::sched::{sched_setaffinity, CpuSet};
    let mut set = CpuSet::new();
    for &c in cpus {
        if let Err(e) = set.set(c) {
            log::warn!("CPU {c} for the {thread} thread is out of range ({e}); ignoring the affinity setting");
            return false;
        }
    }
    match sched_setaffinity(nix::unistd::Pid::from_raw(0), &set) {
        Ok(()) => true,
        Err(e) => {
            log::warn!(
                "could not pin the {thread} thread to CPUs {cpus:?} ({e}); it runs anywhere"
            );
            false
        }
    }
}

/// Reads CLOCK_MONOTONIC.
///
pub fn monotonic_now() -> Micros {
    match nix::time::clock_gettime(nix::time::ClockId::CLOCK_MONOTONIC) {
        Ok(ts) => Micros(ts.tv_sec() as u64 * 1_000_000 + ts.tv_nsec() as u64 / 1_000),
        // CLOCK_MONOTONIC cannot fail on Linux; fall back to zero rather than panic.
        Err(_) => Micros::ZERO,
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn the_worker_thread_runs_at_nice_10() {
        let nice = std::thread::spawn(|| {
            super::make_background("test");
            super::thread_nice()
        })
        .join()
        .unwrap();
        assert_eq!(nice, Some(super::WORKER_NICE));
        // The caller's own thread is untouched.
        assert_ne!(super::thread_nice(), Some(super::WORKER_NICE));
    }
}
