//! SIGINT and SIGTERM during a long `gradvi solve`: the message, the status (128 + the
//! signal's number), and neither the output files nor their temporaries left in the directory.

#![cfg(unix)]

use std::io::{BufRead, BufReader};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

fn interrupted_by(sig: libc::c_int, name: &str, status: i32) {
    let dir = std::env::temp_dir().join(format!("gradvi-interrupt-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    // the paper's cold start on 512 × 512 cells: well over a hundred linear solves
    let mut child = Command::new(env!("CARGO_BIN_EXE_gradvi"))
        .args([
            "solve",
            "--problem",
            "test3",
            "--generate",
            "cartesian",
            "--level",
            "8",
        ])
        .args(["--warm-start", "cold", "--vtu", "u.vtu", "--json", "u.json"])
        .current_dir(&dir)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut stderr = BufReader::new(child.stderr.take().unwrap());
    let mut seen = String::new();
    // wait for the first linear solve of the iteration
    loop {
        let mut line = String::new();
        assert!(
            stderr.read_line(&mut line).unwrap() > 0,
            "ended early: {seen}"
        );
        seen.push_str(&line);
        if line.trim_start().starts_with("solve ") {
            break;
        }
    }
    assert!(
        child.try_wait().unwrap().is_none(),
        "finished too early: {seen}"
    );
    let sent = Instant::now();
    // SAFETY: kill sends a signal to the child this test spawned
    assert_eq!(unsafe { libc::kill(child.id() as libc::pid_t, sig) }, 0);
    let mut rest = String::new();
    std::io::Read::read_to_string(&mut stderr, &mut rest).unwrap();
    let exit = child.wait().unwrap();
    let waited = sent.elapsed();
    assert_eq!(exit.code(), Some(status), "{seen}{rest}");
    assert!(rest.contains(&format!("interrupted ({name})")), "{rest}");
    assert!(waited < Duration::from_secs(60), "{waited:?}");
    let left: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert!(left.is_empty(), "left behind: {left:?}");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn sigint_stops_a_solve_with_status_130_and_no_output() {
    interrupted_by(libc::SIGINT, "SIGINT", 130);
}

#[test]
fn sigterm_stops_a_solve_with_status_143_and_no_output() {
    interrupted_by(libc::SIGTERM, "SIGTERM", 143);
}
