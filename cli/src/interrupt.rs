//! SIGINT and SIGTERM during `gradvi solve`: the first one sets a flag that the solver polls
//! between linear solves ([`gradvi::solver::Cancel`]), so that the solve stops with
//! [`gradvi::Error::Interrupted`], no output is renamed into place and its temporary file is
//! removed ([`crate::output::atomic`]); the process then prints `interrupted (SIGINT)` and
//! exits with 128 + the signal's number (130 for SIGINT, 143 for SIGTERM), as a shell does. A
//! second signal ends the process at once with the same status (a temporary output file being
//! written may then stay behind).

use std::sync::atomic::{AtomicI32, Ordering};

/// The first signal received (0: none). A signal handler can only reach static state.
static RECEIVED: AtomicI32 = AtomicI32::new(0);

#[cfg(unix)]
extern "C" fn on_signal(sig: libc::c_int) {
    // only async-signal-safe operations here: an atomic exchange and _exit
    if RECEIVED.swap(sig, Ordering::SeqCst) != 0 {
        // SAFETY: _exit is async-signal-safe and ends the process without unwinding
        unsafe { libc::_exit(128 + sig) };
    }
}

/// Installs the handlers of SIGINT and SIGTERM (nothing on other platforms, where the default
/// action ends the process).
pub fn install() {
    #[cfg(unix)]
    for sig in [libc::SIGINT, libc::SIGTERM] {
        // SAFETY: the handler only does async-signal-safe operations; a failure (SIG_ERR)
        // leaves the default action, which ends the process
        unsafe {
            libc::signal(sig, on_signal as *const () as libc::sighandler_t);
        }
    }
}

/// The signal received, if any.
pub fn received() -> Option<i32> {
    match RECEIVED.load(Ordering::SeqCst) {
        0 => None,
        s => Some(s),
    }
}

/// The solver's hook: true once a signal was received.
pub fn cancel() -> gradvi::solver::Cancel {
    gradvi::solver::Cancel::new(|| received().is_some())
}

/// `Err(Interrupted)` once a signal was received (checked before an output is put in place).
pub fn check() -> gradvi::Result<()> {
    match received() {
        Some(_) => Err(gradvi::Error::Interrupted),
        None => Ok(()),
    }
}

/// The message and exit status of an interrupted run, if `e` is an interruption by a signal.
pub fn report(e: &anyhow::Error) -> Option<(String, u8)> {
    let sig = received()?;
    let interrupted = e.chain().any(|c| {
        matches!(
            c.downcast_ref::<gradvi::Error>(),
            Some(gradvi::Error::Interrupted)
        )
    });
    if !interrupted {
        return None;
    }
    let name = match sig {
        #[cfg(unix)]
        libc::SIGINT => "SIGINT".to_string(),
        #[cfg(unix)]
        libc::SIGTERM => "SIGTERM".to_string(),
        s => format!("signal {s}"),
    };
    let status = u8::try_from(128 + sig).unwrap_or(1);
    Some((format!("interrupted ({name}): no output written"), status))
}
