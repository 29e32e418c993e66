//! Issue 47, "bad input, round three": `bench load` and `bench live` arguments that panicked,
//! aborted on a 432 TB allocation or blamed the wrong file. The program runs under `ulimit -v`
//! 4 GiB, so an allocation the arguments should have been refused for is an abort, and an
//! abort fails the test.

use std::path::PathBuf;
use std::process::Command;

struct Run {
    code: i32,
    stderr: String,
}

/// Runs `volgraph-bench` with `args` from an empty folder, under a 4 GiB address-space limit.
fn bench(args: &[&str]) -> Run {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("round_three_bench");
    std::fs::create_dir_all(&dir).expect("scratch folder");
    let out = Command::new("timeout")
        .args(["60", "sh", "-c", "ulimit -v 4194304; exec \"$0\" \"$@\""])
        .arg(env!("CARGO_BIN_EXE_volgraph-bench"))
        .args(args)
        .current_dir(&dir)
        .env("RUST_BACKTRACE", "1")
        .output()
        .expect("sh runs volgraph-bench");
    let run = Run { code: out.status.code().unwrap_or(-1), stderr: String::from_utf8_lossy(&out.stderr).into_owned() };
    assert_ne!(run.code, 124, "{args:?} hung:\n{}", run.stderr);
    assert_ne!(run.code, -1, "{args:?} was killed by a signal (an abort?):\n{}", run.stderr);
    assert_ne!(run.code, 101, "{args:?} panicked:\n{}", run.stderr);
    assert!(!run.stderr.contains("memory allocation"), "{args:?} aborted:\n{}", run.stderr);
    run
}

#[test]
fn bench_load_size_0_is_refused_naming_the_flag_and_its_range() {
    for (flag, value) in [("--size", "0"), ("--slices", "0"), ("--size", "60000"), ("--repeats", "0")] {
        let run = bench(&["bench", "load", flag, value]);
        assert_eq!(run.code, 2, "{flag} {value}: {}", run.stderr);
        let range = if flag == "--repeats" { "1..=1000" } else { "1..=4096" };
        assert!(
            run.stderr.contains(&format!("invalid value '{value}' for '{flag}")) && run.stderr.contains(range),
            "{flag} {value}: {}",
            run.stderr
        );
    }
}

#[test]
fn bench_load_too_large_for_memory_is_refused_before_allocating() {
    // 4096 × 4096 × 4096 int16 is 137 GB, five copies of it far more than 4 GiB.
    let run = bench(&["bench", "load", "--size", "4096", "--slices", "4096"]);
    assert_eq!(run.code, 1, "{}", run.stderr);
    assert!(
        run.stderr.contains("--size 4096 --slices 4096: the phantom is 137439 MB of int16")
            && run.stderr.contains("of memory available; choose a smaller --size or --slices"),
        "{}",
        run.stderr
    );
}

#[test]
fn bench_load_just_under_the_address_space_limit_counts_what_the_process_already_uses() {
    // 4096 × 4096 × 25 int16 is 839 MB, five copies 4194 MB: under the 4295 MB of `ulimit -v`
    // 4 GiB, so the whole limit let it through, but not under what the limit leaves once the
    // process's own address space (VmSize) and the margin are counted.
    let run = bench(&["bench", "load", "--size", "4096", "--slices", "25"]);
    assert_eq!(run.code, 1, "{}", run.stderr);
    assert!(
        run.stderr.contains("--size 4096 --slices 25: the phantom is 839 MB of int16")
            && run.stderr.contains("up to 5 copies of it (4194 MB), more than the"),
        "{}",
        run.stderr
    );
    // The figure is the limit's (unless the machine has less memory free than that).
    assert!(
        run.stderr.contains("(available: the address-space limit of 4295 MB less the ")
            && run.stderr.contains("MB this process already uses and a margin of 268 MB)")
            || run.stderr.contains("(available: MemAvailable of /proc/meminfo)"),
        "{}",
        run.stderr
    );
}

#[test]
fn bench_live_with_a_missing_graph_names_the_graph_file_not_a_shaders_folder() {
    let run = bench(&["bench", "live", "--graph", "missing.ron"]);
    assert_eq!(run.code, 1, "{}", run.stderr);
    assert!(run.stderr.contains("missing.ron: cannot read the graph file"), "{}", run.stderr);
    assert!(!run.stderr.contains("shaders"), "{}", run.stderr);
}
