//! Holding the signals that ask a run to stop (Ctrl-C's SIGINT, SIGTERM, SIGHUP) while it
//! writes: a run is one transaction, and a signal that ended the process between two renames
//! would leave some inputs replaced, their backups, temporaries and lock files behind. Held, a
//! signal waits until the transaction has committed or been undone, and then ends the process
//! as it would have (its default action), with every file in one of the two states.
//! (SIGKILL cannot be held: what it leaves is cleaned by the next run, docs/design.md §9.)

/// While alive, the stop signals stay pending; dropped, they are delivered.
pub(crate) struct StopSignalsHeld {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    before: Option<libc::sigset_t>,
}

impl StopSignalsHeld {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    #[allow(unsafe_code)]
    pub(crate) fn new() -> StopSignalsHeld {
        // SAFETY: the sets are plain values initialised by `sigemptyset` before use, and
        // `pthread_sigmask` only changes this thread's mask (the run writes on this thread).
        let before = unsafe {
            let mut set: libc::sigset_t = std::mem::zeroed();
            let mut before: libc::sigset_t = std::mem::zeroed();
            libc::sigemptyset(&mut set);
            for s in [libc::SIGINT, libc::SIGTERM, libc::SIGHUP] {
                libc::sigaddset(&mut set, s);
            }
            (libc::pthread_sigmask(libc::SIG_BLOCK, &set, &mut before) == 0).then_some(before)
        };
        StopSignalsHeld { before }
    }

    #[cfg(not(all(target_os = "linux", target_env = "gnu")))]
    pub(crate) fn new() -> StopSignalsHeld {
        StopSignalsHeld {}
    }
}

impl Drop for StopSignalsHeld {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    #[allow(unsafe_code)]
    fn drop(&mut self) {
        if let Some(before) = &self.before {
            // SAFETY: `before` is the mask `pthread_sigmask` returned; restoring it delivers
            // whatever signal came meanwhile.
            unsafe {
                libc::pthread_sigmask(libc::SIG_SETMASK, before, std::ptr::null_mut());
            }
        }
    }

    #[cfg(not(all(target_os = "linux", target_env = "gnu")))]
    fn drop(&mut self) {}
}
