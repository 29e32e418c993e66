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
/// the run.
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
    let result = runner.run(strategy, |value| {
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
        Ok(())
    });
    FuzzSummary {
        counts: counts.into_inner().unwrap_or_default(),
        slowest: slowest.into_inner().unwrap_or_default(),
        failure: result.err().map(|e| e.to_string()),
    }
}
