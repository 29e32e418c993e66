//! The loop the fuzzers share (`cli_fuzz.rs`, `input_fuzz.rs`): run a proptest strategy's cases,
//! each under `catch_unwind` and a hang limit, count the outcomes, and report the slowest case.

use std::collections::BTreeMap;
use std::fmt::Debug;
use std::sync::Mutex;
use std::time::{Duration, Instant};

use proptest::strategy::Strategy;
use proptest::test_runner::{Config, TestCaseError, TestRunner};

/// What a fuzz run saw.
pub struct FuzzSummary<O> {
    /// Cases per outcome.
    pub counts: BTreeMap<O, u64>,
    /// The slowest case.
    pub slowest: Duration,
    /// The first failing case (a panic, a hang, a wrong outcome), already shrunk.
    pub failure: Option<String>,
}

impl<O> FuzzSummary<O> {
    /// Cases run.
    pub fn total(&self) -> u64 {
        self.counts.values().sum()
    }
}

/// Runs `cases` cases of `strategy`: `case` maps one value to its outcome or to what is wrong,
/// `describe` names the value in a failure. A panic, a case over `hang_seconds` or an `Err` fails
/// the run. A case that never returns (a real hang) is caught by a watchdog thread, which names
/// it and ends the process with exit status 1 after ten times the limit.
pub fn fuzz<S, O>(
    strategy: &S,
    cases: u32,
    hang_seconds: f64,
    describe: impl Fn(&S::Value) -> String,
    case: impl Fn(&S::Value) -> Result<O, String> + std::panic::RefUnwindSafe,
) -> FuzzSummary<O>
where
    S: Strategy,
    S::Value: std::panic::RefUnwindSafe,
    O: Ord + Debug,
{
    let mut runner = TestRunner::new(Config { cases, failure_persistence: None, ..Config::default() });
    let counts = Mutex::new(BTreeMap::<O, u64>::new());
    let slowest = Mutex::new(Duration::ZERO);
    // The case running now: when it started and what it is.
    let current = std::sync::Arc::new(Mutex::new(None::<(Instant, String)>));
    let done = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
    let watchdog = {
        let (current, done) = (current.clone(), done.clone());
        let limit = Duration::from_secs_f64(hang_seconds * 10.0);
        std::thread::spawn(move || {
            while !done.load(std::sync::atomic::Ordering::Relaxed) {
                std::thread::sleep(Duration::from_millis(100));
                if let Ok(c) = current.lock()
                    && let Some((start, what)) = c.as_ref()
                    && start.elapsed() > limit
                {
                    eprintln!("fuzz: a case hung for over {limit:?}: {what}");
                    std::process::exit(1);
                }
            }
        })
    };
    let result = runner.run(strategy, |value| {
        if let Ok(mut c) = current.lock() {
            *c = Some((Instant::now(), describe(&value)));
        }
        let start = Instant::now();
        let outcome = std::panic::catch_unwind(|| case(&value))
            .map_err(|_| TestCaseError::fail(format!("panicked on {}", describe(&value))))?
            .map_err(|e| TestCaseError::fail(format!("{e}\nfor {}", describe(&value))))?;
        let took = start.elapsed();
        if took.as_secs_f64() > hang_seconds {
            return Err(TestCaseError::fail(format!("took {took:?} (a hang) on {}", describe(&value))));
        }
        if let Ok(mut s) = slowest.lock() {
            *s = (*s).max(took);
        }
        if let Ok(mut c) = counts.lock() {
            *c.entry(outcome).or_default() += 1;
        }
        if let Ok(mut c) = current.lock() {
            *c = None;
        }
        Ok(())
    });
    done.store(true, std::sync::atomic::Ordering::Relaxed);
    let _ = watchdog.join();
    FuzzSummary {
        counts: counts.into_inner().unwrap_or_default(),
        slowest: slowest.into_inner().unwrap_or_default(),
        failure: result.err().map(|e| e.to_string()),
    }
}

/// The byte range of the token around `at` (a run of identifier characters, `.` and `-`, or a
/// quoted string): what the fuzzers' mutations replace and swap.
pub fn token_at(bytes: &[u8], at: usize) -> (usize, usize) {
    let word = |b: u8| b.is_ascii_alphanumeric() || b == b'_' || b == b'.' || b == b'-';
    if bytes.is_empty() {
        return (0, 0);
    }
    let at = at.min(bytes.len() - 1);
    if bytes[at] == b'"' {
        let end = bytes[at + 1..].iter().position(|b| *b == b'"').map_or(bytes.len(), |e| at + 2 + e);
        return (at, end);
    }
    let (mut start, mut end) = (at, at);
    while start > 0 && word(bytes[start - 1]) {
        start -= 1;
    }
    while end < bytes.len() && word(bytes[end]) {
        end += 1;
    }
    (start, end.max(start))
}
