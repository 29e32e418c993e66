//! What the loader fuzzers share (issue 47): the case count from `VOLGRAPH_FUZZ_CASES`, and a
//! [`Harness`] that runs each case under `catch_unwind`, times it, counts Ok, Err, panics and
//! cases slower than [`HANG_SECONDS`], keeps the first failure and the slowest case, ends the
//! process from a watchdog thread on a real hang (ten times the limit), and prints the summary
//! line a long run is recorded with.
#![allow(dead_code)] // Each fuzzer uses a different subset of these helpers.

use std::cell::{Cell, RefCell};
use std::fmt::{Debug, Display};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// A case slower than this fails the test; one running ten times as long ends the process.
pub const HANG_SECONDS: f64 = 5.0;

/// The number of cases: `VOLGRAPH_FUZZ_CASES`, else `default`.
pub fn cases(default: u32) -> u32 {
    std::env::var("VOLGRAPH_FUZZ_CASES").ok().and_then(|v| v.parse().ok()).unwrap_or(default)
}

/// Counts and watches the cases of one fuzzer.
pub struct Harness {
    /// Starts every line printed ("nifti fuzz").
    name: &'static str,
    /// A progress line is printed every this many cases.
    progress_every: u64,
    ok: Cell<u64>,
    err: Cell<u64>,
    panics: Cell<u64>,
    slow: Cell<u64>,
    started: Cell<u64>,
    first_failure: RefCell<Option<String>>,
    slowest: Cell<Duration>,
    slowest_case: RefCell<String>,
    /// The case running and when it started, for the watchdog.
    current: Arc<Mutex<Option<(Instant, String)>>>,
    done: Arc<AtomicBool>,
    watchdog: Option<JoinHandle<()>>,
    began: Instant,
}

impl Harness {
    /// Starts the watchdog.
    pub fn new(name: &'static str, progress_every: u64) -> Harness {
        let current = Arc::new(Mutex::new(None::<(Instant, String)>));
        let done = Arc::new(AtomicBool::new(false));
        let watchdog = {
            let (current, done) = (current.clone(), done.clone());
            std::thread::spawn(move || {
                while !done.load(Ordering::Relaxed) {
                    std::thread::sleep(Duration::from_millis(200));
                    if let Ok(c) = current.lock()
                        && let Some((start, what)) = c.as_ref()
                        && start.elapsed().as_secs_f64() > HANG_SECONDS * 10.0
                    {
                        eprintln!("{name}: a case hung for over {}s: {what}", HANG_SECONDS * 10.0);
                        std::process::exit(1);
                    }
                }
            })
        };
        Harness {
            name,
            progress_every,
            ok: Cell::new(0),
            err: Cell::new(0),
            panics: Cell::new(0),
            slow: Cell::new(0),
            started: Cell::new(0),
            first_failure: RefCell::new(None),
            slowest: Cell::new(Duration::ZERO),
            slowest_case: RefCell::new(String::new()),
            current,
            done,
            watchdog: Some(watchdog),
            began: Instant::now(),
        }
    }

    /// Runs `load` for `case`: a panic, a case slower than [`HANG_SECONDS`], or an error whose
    /// message `check_error` finds fault with (its reason) is a failure.
    pub fn run<T, E: Display>(
        &self,
        case: &impl Debug,
        load: impl FnOnce() -> Result<T, E>,
        check_error: impl FnOnce(&str) -> Option<String>,
    ) {
        let n = self.started.get() + 1;
        self.started.set(n);
        if n.is_multiple_of(self.progress_every) {
            eprintln!(
                "{}: {n} cases, {} Ok, {} Err, {} panics, {} slow, {:.0}s",
                self.name,
                self.ok.get(),
                self.err.get(),
                self.panics.get(),
                self.slow.get(),
                self.began.elapsed().as_secs_f64()
            );
        }
        if let Ok(mut c) = self.current.lock() {
            *c = Some((Instant::now(), format!("{case:?}")));
        }
        let start = Instant::now();
        let outcome = std::panic::catch_unwind(std::panic::AssertUnwindSafe(load));
        let took = start.elapsed();
        if let Ok(mut c) = self.current.lock() {
            *c = None;
        }
        if took > self.slowest.get() {
            self.slowest.set(took);
            *self.slowest_case.borrow_mut() = format!("{case:?}");
        }
        let mut failure = None;
        match outcome {
            Ok(Ok(_)) => self.ok.set(self.ok.get() + 1),
            Ok(Err(e)) => {
                self.err.set(self.err.get() + 1);
                failure = check_error(&e.to_string());
            }
            Err(_) => {
                self.panics.set(self.panics.get() + 1);
                failure = Some("panicked".to_string());
            }
        }
        if took.as_secs_f64() > HANG_SECONDS {
            self.slow.set(self.slow.get() + 1);
            failure = Some(format!("took {took:?}"));
        }
        if let Some(what) = failure {
            self.first_failure.borrow_mut().get_or_insert_with(|| format!("{what} on {case:?}"));
        }
    }

    /// Stops the watchdog, prints the summary, and fails the test on the runner's `result`, on
    /// any failure, or when the cases never reached both Ok and Err.
    pub fn finish(mut self, result: Result<(), impl Debug>) {
        self.done.store(true, Ordering::Relaxed);
        if let Some(watchdog) = self.watchdog.take() {
            let _ = watchdog.join();
        }
        let (ok, err, panics) = (self.ok.get(), self.err.get(), self.panics.get());
        eprintln!(
            "{}: {} cases: {ok} Ok, {err} Err, {panics} panics, 0 aborts (the process lived), {} hangs over \
             {HANG_SECONDS}s; slowest {:.1} ms ({}), {:.0}s in all",
            self.name,
            ok + err + panics,
            self.slow.get(),
            self.slowest.get().as_secs_f64() * 1e3,
            self.slowest_case.borrow(),
            self.began.elapsed().as_secs_f64()
        );
        assert!(result.is_ok(), "{result:?}");
        assert_eq!(self.first_failure.take(), None);
        assert!(ok > 0 && err > 0, "both outcomes are reached: {ok} Ok, {err} Err");
    }
}
