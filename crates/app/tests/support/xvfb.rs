//! An Xvfb server for the window tests (`viewer_window.rs`, `bad_input_round_three_views.rs`),
//! on a free display of a range each test binary keeps to itself so that they can run at once.
//! A display whose lock file names a process that is gone (an Xvfb killed before it could
//! clean up) is taken over: its lock and socket are removed. The server is killed on drop and
//! its lock and socket removed, so runs do not use up the range.

use std::path::PathBuf;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

/// A running Xvfb.
pub struct Xvfb {
    child: Child,
    number: u32,
    /// `:N`, for `DISPLAY`.
    pub display: String,
}

impl Drop for Xvfb {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
        remove_display_files(self.number);
    }
}

fn lock_path(n: u32) -> PathBuf {
    PathBuf::from(format!("/tmp/.X{n}-lock"))
}

fn socket_path(n: u32) -> PathBuf {
    PathBuf::from(format!("/tmp/.X11-unix/X{n}"))
}

fn remove_display_files(n: u32) {
    let _ = std::fs::remove_file(lock_path(n));
    let _ = std::fs::remove_file(socket_path(n));
}

/// Whether display `n` is in use: its lock names a live process (a lock without one, or a
/// socket without a lock, is what a killed server left behind).
fn in_use(n: u32) -> bool {
    match std::fs::read_to_string(lock_path(n)) {
        Ok(text) => match text.trim().parse::<u32>() {
            Ok(pid) => std::path::Path::new(&format!("/proc/{pid}")).exists(),
            // Being written by a server that is starting.
            Err(_) => true,
        },
        Err(_) => false,
    }
}

/// Starts Xvfb with a `screen` (`WxHxD`) on the first free display of `displays`; `None` (a
/// note) where Xvfb is not installed, which under CI is a failure.
pub fn start_xvfb(displays: std::ops::Range<u32>, screen: &str) -> Option<Xvfb> {
    // One start at a time in this process: two tests running at once both found display n free,
    // and the second's clean-up of "stale" files removed the first server's lock, so both ran on
    // one server and the first to finish killed it under the other ("XIO: fatal IO error 104").
    static STARTING: std::sync::Mutex<()> = std::sync::Mutex::new(());
    let _one_at_a_time = STARTING.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
    let found = Command::new("Xvfb").arg("-help").stdout(Stdio::null()).stderr(Stdio::null()).status().is_ok();
    if !found {
        assert!(
            std::env::var_os("CI").is_none(),
            "Xvfb is missing under CI; .ci/run installs it (apt-get install xvfb)"
        );
        eprintln!("note: skipping a window test: Xvfb is not installed (apt-get install xvfb)");
        return None;
    }
    for n in displays {
        if in_use(n) {
            continue;
        }
        remove_display_files(n);
        let Ok(child) = Command::new("Xvfb")
            .args([format!(":{n}"), "-screen".into(), "0".into(), screen.into(), "-nolisten".into(), "tcp".into()])
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
        else {
            continue;
        };
        let mut server = Xvfb { child, number: n, display: format!(":{n}") };
        let start = Instant::now();
        while start.elapsed() < Duration::from_secs(10) {
            // Its own socket: a server that has exited (another took the display) is not ours.
            if server.child.try_wait().ok().flatten().is_some() {
                break;
            }
            if socket_path(n).exists() {
                return Some(server);
            }
            std::thread::sleep(Duration::from_millis(50));
        }
        // Dropping kills it and clears what it left.
        drop(server);
    }
    panic!("no free X display for Xvfb");
}
