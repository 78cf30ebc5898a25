//! `mcp-gs` on a serial link that can never be a serial port, or that ends for good
//! while `radio` or `sim` run: refused, or stopped, with the link named, rather than
//! waited for forever.
//!
//! Unix only, the whole file: every test runs `mcp-gs` on a device path (`/dev/null`,
//! a pseudo-terminal's far end), and all but one need Linux.
#![cfg(unix)]

#[cfg(target_os = "linux")]
use serialport::SerialPort;
use std::process::{Command, Stdio};
use std::sync::mpsc::{Receiver, RecvTimeoutError};

mod common;

use common::{GUARD, Running};

/// Starts `mcp-gs` with `args`, its standard output and error each line by line on a
/// channel; the process is killed when the returned guard is dropped.
fn start(args: &[&str]) -> (Running, Receiver<String>, Receiver<String>) {
    start_as(Command::new(env!("CARGO_BIN_EXE_mcp-gs")), args)
}

/// [`start`], with `command` (`mcp-gs`, or a program that runs it as another user).
fn start_as(mut command: Command, args: &[&str]) -> (Running, Receiver<String>, Receiver<String>) {
    let mut child = command
        .args(args)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("start mcp-gs");
    let stdout = common::stdout_lines(&mut child);
    let stderr = common::stderr_lines(&mut child);
    (Running(child), stdout, stderr)
}

/// The lines still to come on `lines` until the process closes it (it ends), and its
/// exit code; a process still running after [`GUARD`] fails the test.
fn finish(mut running: Running, lines: &Receiver<String>, args: &[&str]) -> (Option<i32>, String) {
    let mut said = String::new();
    loop {
        match lines.recv_timeout(GUARD) {
            Ok(line) => {
                said.push_str(&line);
                said.push('\n');
            }
            Err(RecvTimeoutError::Disconnected) => break,
            Err(RecvTimeoutError::Timeout) => panic!("{args:?} still runs: {said}"),
        }
    }
    let status = running.0.wait().expect("wait for mcp-gs");
    (status.code(), said)
}

/// The next line on `lines` that satisfies `f`; the others are dropped.
#[cfg(target_os = "linux")]
fn line(lines: &Receiver<String>, mut f: impl FnMut(&str) -> bool) -> String {
    loop {
        let line = lines.recv_timeout(GUARD).expect("a line in time");
        if f(&line) {
            return line;
        }
    }
}

#[cfg(unix)]
#[test]
fn a_path_that_can_never_be_a_serial_port_is_refused_at_once() {
    let dir = tempfile::tempdir().unwrap();
    // What `echo > /dev/ttyUSB0` leaves before the adapter is plugged in.
    let file = dir.path().join("ttyUSB0");
    std::fs::write(&file, b"\n").unwrap();
    for (path, what) in [
        (file.to_str().unwrap(), "a regular file"),
        ("/dev/null", "a device that is no terminal"),
    ] {
        let link = format!("serial:{path}");
        // `radio` and `sim` would otherwise run until then, and exit 0.
        let commands: [&[&str]; 4] = [
            &["sim", "--link", &link, "--duration", "10"],
            &["radio", "--coordinator", &link, "--duration", "10"],
            &["monitor", "--wait", "--link", &link],
            &["hub", "--wait", "--link", &link, "--listen", "127.0.0.1:0"],
        ];
        for args in commands {
            let (running, stdout, stderr) = start(args);
            let (code, said) = finish(running, &stderr, args);
            assert_eq!(code, Some(3), "{args:?}: {said}");
            assert_eq!(
                said,
                format!(
                    "mcp-gs: cannot open {link}:115200: {path} is not a serial device but \
                     {what} (`mcp-gs ports` lists the serial ports present)\n"
                ),
                "{args:?}"
            );
            // Nothing started: not a line on standard output, which is closed.
            assert_eq!(
                stdout.recv_timeout(GUARD),
                Err(RecvTimeoutError::Disconnected),
                "{args:?}"
            );
        }
    }
}

/// A pseudo-terminal pair: the master side, the far end (held open, so that the master
/// side reads what comes), and the far end's path, a terminal device as a USB serial
/// adapter's is. Neither is inherited by the processes started: closing them here closes
/// them.
#[cfg(target_os = "linux")]
fn pseudo_terminal() -> (serialport::TTYPort, serialport::TTYPort, String) {
    use std::os::fd::AsRawFd;
    let (master, far) = serialport::TTYPort::pair().expect("a pseudo-terminal pair");
    for fd in [master.as_raw_fd(), far.as_raw_fd()] {
        // SAFETY: F_SETFD takes an int and touches nothing but the descriptor's flags;
        // the descriptor is open for the call.
        let done = unsafe { libc::fcntl(fd, libc::F_SETFD, libc::FD_CLOEXEC) };
        assert_eq!(done, 0, "FD_CLOEXEC: {}", std::io::Error::last_os_error());
    }
    let path = far.name().expect("the far end's path");
    (master, far, path)
}

/// Points the symbolic link `at` to `target`, at once (as a device node replaced).
#[cfg(target_os = "linux")]
fn repoint(at: &std::path::Path, target: &std::path::Path) {
    let next = at.with_extension("next");
    std::os::unix::fs::symlink(target, &next).unwrap();
    std::fs::rename(&next, at).unwrap();
}

/// A USB serial adapter's path in `dir`, `ttyUSB0`, a terminal at first: a symbolic
/// link to a pseudo-terminal's far end. The master side and the far end (held open) come
/// with it.
#[cfg(target_os = "linux")]
fn adapter(
    dir: &std::path::Path,
) -> (serialport::TTYPort, serialport::TTYPort, std::path::PathBuf) {
    let (master, far, terminal) = pseudo_terminal();
    let port = dir.join("ttyUSB0");
    std::os::unix::fs::symlink(&terminal, &port).unwrap();
    (master, far, port)
}

/// The adapter at `port` pulled out, and a regular file left where it was: the link
/// goes down, and cannot be opened again.
#[cfg(target_os = "linux")]
fn pull_out(
    dir: &std::path::Path,
    port: &std::path::Path,
    master: serialport::TTYPort,
    far: serialport::TTYPort,
) {
    drop(far);
    let stray = dir.join("stray");
    std::fs::write(&stray, b"\n").unwrap();
    repoint(port, &stray);
    drop(master);
}

#[cfg(target_os = "linux")]
#[test]
fn a_link_that_ends_for_good_stops_sim_and_radio_naming_it() {
    let mav = "0013a20040b599b9";
    let cases: [(&[&str], String); 2] = [
        (&["sim", "--link"], "the ground station's link".into()),
        (
            &["radio", "--coordinator", "tcp-listen:127.0.0.1:0", "--node"],
            format!("node {mav}'s link"),
        ),
    ];
    for (command, name) in cases {
        let dir = tempfile::tempdir().unwrap();
        let (mut master, far, port) = adapter(dir.path());
        let link = format!("serial:{}", port.display());
        let given = match command[0] {
            "sim" => link.clone(),
            _ => format!("{mav}={link}"),
        };
        let mut args = command.to_vec();
        args.push(&given);
        let (running, _stdout, stderr) = start(&args);
        // Open: the node's radio hands its device a modem status.
        master.set_timeout(GUARD).unwrap();
        let mut start = [0u8; 1];
        std::io::Read::read_exact(&mut master, &mut start).expect("a modem status");
        assert_eq!(start, [0x7E]);
        pull_out(dir.path(), &port, master, far);
        let (code, said) = finish(running, &stderr, &args);
        assert_eq!(code, Some(3), "{args:?}: {said}");
        let path = port.display();
        assert!(
            said.starts_with(&format!(
                "mcp-gs: {name} {link}:115200 ended: it cannot be opened, and waiting will \
                 not change that: "
            )) && said.ends_with(&format!(
                " (not a serial port ({path} is a regular file): `mcp-gs ports` lists the \
                 serial ports present)\n"
            )),
            "{args:?}: {said}"
        );
        assert!(!said.contains("warning"), "{args:?}: {said}");
    }
}

/// A command that runs `mcp-gs` as an unprivileged user, for a device it may not open:
/// itself when this test is not run by root, else `setpriv` as `nobody`; `None` where
/// neither can be (no `setpriv`, or a binary `nobody` may not run).
#[cfg(target_os = "linux")]
fn unprivileged() -> Option<Command> {
    let gs = env!("CARGO_BIN_EXE_mcp-gs");
    // This process's directory belongs to its effective user.
    let uid = std::os::unix::fs::MetadataExt::uid(&std::fs::metadata("/proc/self").unwrap());
    if uid != 0 {
        return Some(Command::new(gs));
    }
    let nobody = || {
        let mut command = Command::new("setpriv");
        command
            .args(["--reuid=65534", "--regid=65534", "--clear-groups", gs])
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(Stdio::null());
        command
    };
    let runs = nobody()
        .arg("--version")
        .status()
        .is_ok_and(|s| s.success());
    runs.then(nobody)
}

#[cfg(target_os = "linux")]
#[test]
fn a_device_this_user_may_not_open_says_what_to_do_also_while_waiting() {
    let Some(_) = unprivileged() else {
        // Straight to the process's stderr, past the harness's capture: said in every run.
        let _ = std::io::Write::write_all(
            &mut std::io::stderr(),
            b"SKIPPED a_device_this_user_may_not_open_says_what_to_do_also_while_waiting: \
              root, and no way to run mcp-gs as another user (setpriv, and a user nobody)\n",
        );
        return;
    };
    let (_master, _far, terminal) = pseudo_terminal();
    std::fs::set_permissions(
        &terminal,
        std::os::unix::fs::PermissionsExt::from_mode(0o000),
    )
    .unwrap();
    let link = format!("serial:{terminal}");
    let hint = "this user may not open the device: on Linux, add the user to the group that \
                owns it (often dialout: `sudo usermod -aG dialout $USER`, then log in again)";

    // Waited for, as a device whose permissions are being set up; what to do is said
    // first, once.
    let args = ["monitor", "--wait", "--link", &link];
    let (_running, _, stderr) = start_as(unprivileged().unwrap(), &args);
    let first = line(&stderr, |_| true);
    assert_eq!(
        first,
        format!("mcp-gs: warning: cannot open {terminal} yet: {hint}")
    );
    let waiting = line(&stderr, |_| true);
    assert!(
        waiting.starts_with("mcp-gs: warning: link not there yet: waiting for it: "),
        "{waiting}"
    );

    // Not waited for by `sim`: refused at once, as `monitor` without --wait does.
    let args = ["sim", "--link", &link, "--duration", "10"];
    let (running, _, stderr) = start_as(unprivileged().unwrap(), &args);
    let (code, said) = finish(running, &stderr, &args);
    assert_eq!(code, Some(3), "{said}");
    assert_eq!(
        said,
        format!("mcp-gs: cannot open {link}:115200: permission denied ({hint})\n")
    );
}

#[cfg(target_os = "linux")]
#[test]
fn a_hub_recording_whose_radio_ends_for_good_says_what_it_recorded() {
    let dir = tempfile::tempdir().unwrap();
    let (mut master, far, port) = adapter(dir.path());
    let link = format!("serial:{}", port.display());
    let record = dir.path().join("flight.mcprec");
    let args = [
        "hub",
        "--link",
        &link,
        "--listen",
        "127.0.0.1:0",
        "--record",
        record.to_str().unwrap(),
    ];
    let (running, stdout, stderr) = start(&args);
    // The hub asks its AT AP twice, unanswered here: it warns, and serves. Both are
    // recorded (4 bytes of frame data each).
    line(&stdout, |l| l.starts_with("serving "));
    // A frame from the radio, recorded: a modem status.
    std::io::Write::write_all(&mut master, &[0x7E, 0x00, 0x02, 0x8A, 0x06, 0x6F]).unwrap();
    // The adapter pulled out once the three frames are in the file (until then the hub
    // is given time: its reads are not seen): the link ends for good.
    let wait = std::time::Instant::now();
    let all = 8 + 2 * mcp_host::record::record_len(4) + mcp_host::record::record_len(2);
    while std::fs::metadata(&record).map_or(0, |m| m.len()) < all as u64 {
        assert!(wait.elapsed() < GUARD, "the frame is not recorded");
        // Looked at again shortly: the file says nothing when it grows.
        std::thread::sleep(std::time::Duration::from_millis(10));
    }
    pull_out(dir.path(), &port, master, far);
    let (code, said) = finish(running, &stderr, &args);
    assert_eq!(code, Some(3), "{said}");
    assert!(!said.contains("panicked"), "{said}");
    let out: Vec<String> = stdout.try_iter().collect();
    assert!(
        out.contains(&format!("recorded 3 frames to {}", record.display())),
        "{out:?}"
    );
}
