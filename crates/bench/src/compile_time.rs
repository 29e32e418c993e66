//! `volgraph bench compile`: how fast a graph compiles and how much transient memory pooling
//! saves.
//!
//! (a) Compile time: a generated 30-pass graph (a chain of ray-direction passes, eight raycast
//! branches with presents, a 4-iteration repeat group with carried feedback, and two passes
//! nothing reads, which are culled) built from the built-in kinds, compiled by
//! [`volgraph_core::compile()`] many times; the median must stay under 1 ms so a hot-reloading
//! viewer can recompile on every keystroke.
//! (b) Memory: every graph under `graphs/` (except `graphs/tf/`, transfer functions) compiled at
//! 1920x1080 with no features; [`volgraph_core::Plan::memory`] gives the pooled and unpooled peak
//! transient bytes; the generated graph's row comes first.
//!
//! (c) Scaling: Krüger–Westermann's RC-a graph with its segment loop fixed at 256 … 4096
//! iterations (the limit); compile time per unrolled step should stay flat (linear compile).
//!
//! Prints markdown tables; writes the same figures as JSON when asked. Never asserts a timing.

use std::fmt::Write as _;
use std::path::Path;
use std::time::Instant;

use anyhow::Context;
use serde::Serialize;
use volgraph_core::{CompileOptions, compile};

/// Warm-up compilations before timing (caches, allocator).
const WARMUP: usize = 50;
/// Timed compilations; each is timed on its own and the median reported.
const ITERATIONS: usize = 2000;
/// The goal for one compilation of the 30-pass graph.
const GOAL_US: f64 = 1000.0;

/// Compile-time figures of the generated graph.
#[derive(Clone, Debug, Serialize)]
pub struct CompileTiming {
    /// Pass declarations in the graph text (repeat bodies counted once).
    pub passes: usize,
    /// Steps in the plan (repeat groups unrolled, culled passes dropped).
    pub steps: usize,
    /// Timed compilations.
    pub iterations: usize,
    /// Median time of one compilation, µs.
    pub median_us: f64,
    /// 10th percentile, µs.
    pub p10_us: f64,
    /// 90th percentile, µs.
    pub p90_us: f64,
    /// The goal, µs.
    pub goal_us: f64,
}

/// Pooled vs unpooled transient memory of one graph file.
#[derive(Clone, Debug, Serialize)]
pub struct GraphMemory {
    /// The file, relative to the graphs folder's parent.
    pub file: String,
    /// Steps in the plan (`None` when the graph does not compile).
    pub steps: Option<usize>,
    /// Physical transient textures.
    pub slots: Option<usize>,
    /// Bytes of the pooled transient textures.
    pub pooled_bytes: Option<u64>,
    /// Bytes if every transient value had its own texture.
    pub unpooled_bytes: Option<u64>,
    /// Bytes of history textures (current + previous frame).
    pub history_bytes: Option<u64>,
    /// The diagnostics when the graph does not compile.
    pub error: Option<String>,
}

/// Compile time of an unrolled repeat group of one size.
#[derive(Clone, Debug, Serialize)]
pub struct ScalingRow {
    /// Iterations of the segment loop.
    pub iterations: u32,
    /// Steps in the plan.
    pub steps: usize,
    /// Median compile time, ms.
    pub median_ms: f64,
    /// Median µs per step.
    pub us_per_step: f64,
}

/// Everything `volgraph bench compile` measures (the JSON report).
#[derive(Clone, Debug, Serialize)]
pub struct CompileBenchReport {
    /// Viewport of the memory figures.
    pub viewport: (u32, u32),
    /// Compile time of the generated 30-pass graph.
    pub timing: CompileTiming,
    /// Compile time vs unrolled size.
    pub scaling: Vec<ScalingRow>,
    /// Memory of each graph file.
    pub graphs: Vec<GraphMemory>,
}

/// Runs the benchmark: prints markdown tables to stdout and writes the JSON report to
/// `json_out` when given.
pub fn run(json_out: Option<&Path>) -> anyhow::Result<()> {
    let report = measure()?;
    volgraph_app::stdout::write_stdout(&to_markdown(&report))?;
    if let Some(path) = json_out {
        let json = serde_json::to_string_pretty(&report).context("serializing the report")?;
        std::fs::write(path, json).with_context(|| format!("writing {}", path.display()))?;
        volgraph_app::stdout::write_stdout(&format!("\nJSON written to {}\n", path.display()))?;
    }
    Ok(())
}

/// Measures (a) and (b) without printing.
pub fn measure() -> anyhow::Result<CompileBenchReport> {
    let timing = time_generated_graph()?;
    let viewport = (1920, 1080);
    let mut graphs = vec![memory_of("(generated bench_30)", &thirty_pass_graph(), viewport)];
    graphs.extend(graph_files()?.iter().map(|(text, name)| memory_of(name, text, viewport)));
    Ok(CompileBenchReport { viewport, timing, scaling: time_scaling()?, graphs })
}

/// (c): RC-a with `Fixed(n)` segments, n = 256 … 4096.
fn time_scaling() -> anyhow::Result<Vec<ScalingRow>> {
    let path = Path::new("kruger_westermann_2003/rc_a");
    let source = volgraph_app::inputs::read_graph(path)?;
    let count = "count: Scene(name: \"longest_ray_voxels\", divide_by_inputs: [\"step_voxels\", \"segment_steps\"])";
    anyhow::ensure!(
        source.contains(count),
        "{} no longer has the segment count this benchmark replaces",
        path.display()
    );
    let registry = volgraph_app::registry();
    let options = CompileOptions::new(512, 512);
    let mut rows = Vec::new();
    for n in [256u32, 512, 1024, 2048, 4096] {
        let text = source.replace(count, &format!("count: Fixed({n})"));
        let plan = compile("rc_a.ron", &text, &registry, &options).map_err(|d| anyhow::anyhow!("{d}"))?;
        let repeats = (40_000 / n as usize).clamp(5, 200);
        let mut ms: Vec<f64> = (0..repeats)
            .map(|_| {
                let start = Instant::now();
                std::hint::black_box(compile("rc_a.ron", &text, &registry, &options).ok());
                start.elapsed().as_secs_f64() * 1e3
            })
            .collect();
        ms.sort_by(f64::total_cmp);
        let median_ms = ms[ms.len() / 2];
        rows.push(ScalingRow {
            iterations: n,
            steps: plan.steps.len(),
            median_ms,
            us_per_step: median_ms * 1e3 / plan.steps.len() as f64,
        });
    }
    Ok(rows)
}

/// The generated 30-pass graph: `entry` → a chain `d1..d10` of direction passes; raycasts
/// `r1..r8` branch off the chain (alternating fragment and compute) and five of them are
/// presented; a repeat group refines `d10`'s output over 4 iterations; a final raycast and
/// present read the group's result; `x1`, `x2` are read by nothing and culled.
pub fn thirty_pass_graph() -> String {
    let mut passes: Vec<String> = vec![r#"Pass(id: "entry", kind: "entry_points")"#.to_string()];
    for i in 1..=10 {
        let src = if i == 1 { "entry.entry".to_string() } else { format!("d{}.dir", i - 1) };
        passes.push(format!(r#"Pass(id: "d{i}", kind: "ray_directions", inputs: {{"entry": "{src}"}})"#));
    }
    let mut outputs =
        vec![r#""image": "final.color""#.to_string(), r#""display": "final_present.display""#.to_string()];
    for k in 1..=8 {
        let kind = if k % 2 == 0 { "raycast_compute" } else { "raycast" };
        passes.push(format!(
            r#"Pass(id: "r{k}", kind: "{kind}", params: {{"step_voxels": 0.5}}, inputs: {{"entry": "entry.entry", "dir": "d{}.dir", "volume": "input.volume", "tf": "input.tf"}})"#,
            k + 2
        ));
        if k <= 5 {
            passes.push(format!(r#"Pass(id: "p{k}", kind: "present", inputs: {{"color": "r{k}.color"}})"#));
            outputs.push(format!(r#""display{k}": "p{k}.display""#));
        } else {
            outputs.push(format!(r#""image{k}": "r{k}.color""#));
        }
    }
    passes.push(
        r#"Repeat(id: "refine", count: Fixed(4), carry: {"v": (init: "d10.dir", next: "b2.dir")}, body: [
            Pass(id: "b1", kind: "ray_directions", inputs: {"entry": "refine.v"}),
            Pass(id: "b2", kind: "ray_directions", inputs: {"entry": "b1.dir"}),
        ])"#
        .to_string(),
    );
    passes.push(
        r#"Pass(id: "final", kind: "raycast", inputs: {"entry": "entry.entry", "dir": "refine.v", "volume": "input.volume", "tf": "input.tf"})"#
            .to_string(),
    );
    passes.push(r#"Pass(id: "final_present", kind: "present", inputs: {"color": "final.color"})"#.to_string());
    passes.push(r#"Pass(id: "x1", kind: "ray_directions", inputs: {"entry": "d5.dir"})"#.to_string());
    passes.push(r#"Pass(id: "x2", kind: "ray_directions", inputs: {"entry": "x1.dir"})"#.to_string());
    format!(
        "Graph(\n    name: \"bench_30\",\n    inputs: {{\"volume\": Volume, \"tf\": TransferFunction}},\n    passes: [\n        {}\n    ],\n    outputs: {{{}}},\n)\n",
        passes.join(",\n        "),
        outputs.join(", ")
    )
}

fn time_generated_graph() -> anyhow::Result<CompileTiming> {
    let text = thirty_pass_graph();
    let registry = volgraph_app::registry();
    let options = CompileOptions::new(1920, 1080);
    let plan = compile("bench_30.ron", &text, &registry, &options)
        .map_err(|d| anyhow::anyhow!("the generated benchmark graph does not compile:\n{d}"))?;
    let passes = text.matches("Pass(").count();
    for _ in 0..WARMUP {
        std::hint::black_box(compile("bench_30.ron", &text, &registry, &options).ok());
    }
    let mut us: Vec<f64> = (0..ITERATIONS)
        .map(|_| {
            let start = Instant::now();
            std::hint::black_box(compile("bench_30.ron", std::hint::black_box(&text), &registry, &options).ok());
            start.elapsed().as_secs_f64() * 1e6
        })
        .collect();
    us.sort_by(f64::total_cmp);
    let at = |q: f64| us[((us.len() - 1) as f64 * q).round() as usize];
    Ok(CompileTiming {
        passes,
        steps: plan.steps.len(),
        iterations: ITERATIONS,
        median_us: at(0.5),
        p10_us: at(0.1),
        p90_us: at(0.9),
        goal_us: GOAL_US,
    })
}

/// `(text, display name)` of every graph built into the program (the graphs of `graphs/`
/// without the transfer functions), in name order: the figures need no source tree.
fn graph_files() -> anyhow::Result<Vec<(&'static str, String)>> {
    Ok(volgraph_app::builtin_graphs::all().into_iter().map(|g| (g.text, format!("graphs/{}.ron", g.name))).collect())
}

/// Compiles `source` and reads its memory figures; the generated graph comes through here too
/// (unlike the repository's graphs, its long chain lets pooling reuse textures).
fn memory_of(name: &str, source: &str, viewport: (u32, u32)) -> GraphMemory {
    let failed = |error: String| GraphMemory {
        file: name.to_string(),
        steps: None,
        slots: None,
        pooled_bytes: None,
        unpooled_bytes: None,
        history_bytes: None,
        error: Some(error),
    };
    match compile(name, source, &volgraph_app::registry(), &CompileOptions::new(viewport.0, viewport.1)) {
        Ok(plan) => {
            let m = plan.memory();
            GraphMemory {
                file: name.to_string(),
                steps: Some(plan.steps.len()),
                slots: Some(plan.slots.iter().filter(|s| !s.persistent).count()),
                pooled_bytes: Some(m.pooled_bytes),
                unpooled_bytes: Some(m.unpooled_bytes),
                history_bytes: Some(m.history_bytes),
                error: None,
            }
        }
        Err(d) => failed(d.to_string()),
    }
}

fn mib(bytes: u64) -> f64 {
    bytes as f64 / (1024.0 * 1024.0)
}

/// The report as markdown tables.
pub fn to_markdown(r: &CompileBenchReport) -> String {
    let mut s = String::new();
    let t = &r.timing;
    let _ = writeln!(s, "## Compile time (generated graph, {} passes → {} steps)\n", t.passes, t.steps);
    let _ = writeln!(s, "| iterations | median µs | p10 µs | p90 µs | goal µs | median / goal |");
    let _ = writeln!(s, "|---:|---:|---:|---:|---:|---:|");
    let _ = writeln!(
        s,
        "| {} | {:.1} | {:.1} | {:.1} | {:.0} | {:.2} |\n",
        t.iterations,
        t.median_us,
        t.p10_us,
        t.p90_us,
        t.goal_us,
        t.median_us / t.goal_us
    );
    if let Some(first) = r.scaling.first() {
        let _ = writeln!(s, "## Compile time vs unrolled size (K-W RC-a, segment loop Fixed(n))\n");
        let _ = writeln!(s, "| iterations | steps | median ms | µs per step | per step vs n = {} |", first.iterations);
        let _ = writeln!(s, "|---:|---:|---:|---:|---:|");
        for row in &r.scaling {
            let _ = writeln!(
                s,
                "| {} | {} | {:.2} | {:.2} | {:.2} |",
                row.iterations,
                row.steps,
                row.median_ms,
                row.us_per_step,
                row.us_per_step / first.us_per_step
            );
        }
        let _ = writeln!(s);
    }
    let _ = writeln!(s, "## Transient memory at {}x{}, no features\n", r.viewport.0, r.viewport.1);
    let _ = writeln!(s, "| graph | steps | slots | pooled MiB | unpooled MiB | pooled / unpooled | history MiB |");
    let _ = writeln!(s, "|---|---:|---:|---:|---:|---:|---:|");
    for g in &r.graphs {
        match (g.steps, g.slots, g.pooled_bytes, g.unpooled_bytes, g.history_bytes) {
            (Some(steps), Some(slots), Some(p), Some(u), Some(h)) => {
                let ratio = if u > 0 { format!("{:.2}", p as f64 / u as f64) } else { "-".to_string() };
                let _ = writeln!(
                    s,
                    "| {} | {steps} | {slots} | {:.1} | {:.1} | {ratio} | {:.1} |",
                    g.file,
                    mib(p),
                    mib(u),
                    mib(h)
                );
            }
            _ => {
                let first = g.error.as_deref().and_then(|e| e.lines().next()).unwrap_or("failed");
                let _ = writeln!(s, "| {} | does not compile: {} | | | | | |", g.file, first.replace('|', "\\|"));
            }
        }
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn generated_graph_has_thirty_passes_and_culls_two() {
        let text = thirty_pass_graph();
        assert_eq!(text.matches("Pass(").count(), 30);
        let plan = compile("bench_30.ron", &text, &volgraph_app::registry(), &CompileOptions::new(1920, 1080))
            .unwrap_or_else(|d| panic!("{d}\n{text}"));
        assert_eq!(plan.culled, ["x1", "x2"]);
        // 28 live passes, the 2-pass body run 4 times instead of once.
        assert_eq!(plan.steps.len(), 28 + 2 * 3);
    }

    #[test]
    fn graph_files_skip_transfer_functions() {
        let files = graph_files().expect("graphs/ is readable");
        assert!(files.iter().any(|(_, n)| n == "graphs/basic/fragment_raycast.ron"), "{files:?}");
        assert!(files.iter().all(|(_, n)| !n.starts_with("graphs/tf/")), "{files:?}");
    }

    /// The benchmark itself, for a run without the CLI:
    /// `cargo test --release -p volgraph-bench compile_time -- --ignored --nocapture`.
    #[test]
    #[ignore = "a measurement, not a test"]
    fn print_the_benchmark() {
        let dir = std::env::temp_dir().join("volgraph_bench_compile.json");
        run(Some(&dir)).expect("the benchmark runs");
    }
}
