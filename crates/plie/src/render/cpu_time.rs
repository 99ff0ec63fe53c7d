//! The process's CPU time (user + system, all threads), beside wall-clock time: on a shared, busy
//! machine the wall time of a pass grows with the other load, its CPU time much less. Reported as
//! `shading_cpu_seconds` by `plie render --json` and used by `plie bench` next to the wall times.

/// CPU seconds used so far by the whole process (all threads), or `None` where it cannot be read.
pub fn process_cpu_seconds() -> Option<f64> {
    #[cfg(unix)]
    {
        let mut u = std::mem::MaybeUninit::<libc::rusage>::uninit();
        // SAFETY: `getrusage` fills the struct it is given; RUSAGE_SELF is always valid.
        let r = unsafe { libc::getrusage(libc::RUSAGE_SELF, u.as_mut_ptr()) };
        if r != 0 {
            return None;
        }
        // SAFETY: initialised by the successful call above.
        let u = unsafe { u.assume_init() };
        let secs = |t: libc::timeval| t.tv_sec as f64 + t.tv_usec as f64 * 1e-6;
        Some(secs(u.ru_utime) + secs(u.ru_stime))
    }
    #[cfg(not(unix))]
    {
        None
    }
}
