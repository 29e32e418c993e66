//! The command-line fuzzer: random `plan` and `render` command lines built from every flag with
//! hostile values (empty, huge, negative, NaN, wrong shapes, unicode, a byte-order mark) and
//! paths to real and broken files of every kind. Each line is parsed by clap and then checked as
//! `volgraph` would before opening the GPU ([`crate::cli::check`]). The property: no panic, no
//! hang (each case well under `HANG_SECONDS`), and the right exit code — 2 for a line clap
//! rejects, 1 with a non-empty message for a checked input that is wrong, 0 otherwise.
//!
//! `VOLGRAPH_FUZZ_CASES` sets the number of cases (default 256 in CI); the summary line gives the
//! counts a long run is recorded with.

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use clap::Parser;
use proptest::prelude::*;

use crate::cli::{Cli, CliError, check};

const HANG_SECONDS: f64 = 5.0;

fn cases() -> u32 {
    std::env::var("VOLGRAPH_FUZZ_CASES").ok().and_then(|v| v.parse().ok()).unwrap_or(256)
}

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// Small files of every kind the flags take, made once.
fn files() -> &'static Vec<String> {
    static FILES: OnceLock<Vec<String>> = OnceLock::new();
    FILES.get_or_init(|| {
        let dir = std::env::temp_dir().join(format!("volgraph-cli-fuzz-{}", std::process::id()));
        let _ = std::fs::create_dir_all(dir.join("a_dir_4x4x4_uint8.raw"));
        let write = |name: &str, bytes: &[u8]| {
            let p = dir.join(name);
            let _ = std::fs::write(&p, bytes);
            p.display().to_string()
        };
        let mut out = vec![
            write("ok_4x4x4_uint8.raw", &[9u8; 64]),
            write("const_4x4x4_uint8.raw", &[0u8; 64]),
            write("short_4x4x4_uint16.raw", &[1u8; 100]),
            write("u16_4x4x4_uint16.raw", &[7u8; 128]),
            write("noname.raw", &[0u8; 8]),
            write("v.nrrd", b"NRRD0004\ntype: uchar\ndimension: 3\nsizes: 2 2 2\nspace directions: (0,-1,0) (1,0,0) (0,0,1)\nencoding: raw\n\n\x01\x02\x03\x04\x05\x06\x07\x08"),
            write("bad.nrrd", b"NRRD0004\ntype: uchar\ndimension: 3\nsizes: 2 2 2\nspace directions: (0.6,0.8,0) (0,1,0) (0,0,1)\nencoding: raw\n\n12345678"),
            write("missing.nhdr", b"NRRD0004\ntype: uchar\ndimension: 3\nsizes: 2 2 2\nencoding: raw\ndata file: nowhere.raw\n"),
            write("v.mha", b"NDims = 3\nDimSize = 2 2 2\nElementType = MET_SHORT\nElementByteOrderMSB = True\nElementDataFile = LOCAL\n0123456789abcdef"),
            write("tf.ron", std::fs::read(root().join("graphs/tf/sparse.ron")).unwrap_or_default().as_slice()),
            write("bad_tf.ron", b"(domain: (1, 0), points: [])"),
            write("maps.json", br#"[{"Name": "A", "RGBPoints": [0,0,0,0,1,1,1,1]}, {"Name": "B", "RGBPoints": [0,1,0,0,1,1,0,0]}]"#),
            write("range.json", br#"[{"RGBPoints": [0,0,0,0,1,1,2,1]}]"#),
            write("bom.json", "\u{feff}[{\"RGBPoints\": [0,0,0,0,1,1,1,1]}]".as_bytes()),
            write("empty.ron", b""),
            dir.join("a_dir_4x4x4_uint8.raw").display().to_string(),
            dir.join("nonexistent.raw").display().to_string(),
            dir.join("out.png").display().to_string(),
            dir.join("out.exr").display().to_string(),
            dir.join("out.jpg").display().to_string(),
            dir.join("out").display().to_string(),
            "/dev/null".to_string(),
        ];
        for sub in ["graphs/basic", "graphs/kruger_westermann_2003", "graphs/modern", "tests/graphs/malformed"] {
            if let Ok(entries) = std::fs::read_dir(root().join(sub)) {
                let mut ron: Vec<String> = entries
                    .filter_map(|e| e.ok().map(|e| e.path()))
                    .filter(|p| p.extension().is_some_and(|e| e == "ron"))
                    .map(|p| p.display().to_string())
                    .collect();
                ron.sort();
                out.extend(ron);
            }
        }
        out
    })
}

/// Values chosen to break parsers: shapes, ranges, encodings.
const HOSTILE: &[&str] = &[
    "",
    " ",
    "0",
    "1",
    "-1",
    "nan",
    "NaN",
    "inf",
    "-inf",
    "1e309",
    "18446744073709551616",
    "4294967296",
    "512x512",
    "0x0",
    "16385x16",
    "64X64",
    "x",
    "64x",
    "x64",
    "1x1",
    "2x2x2",
    "0x4x4",
    "4x4x4x4",
    "4x4",
    "30,20,3.2",
    "30,95,3",
    "30,20,-1",
    "30,20,0",
    "1,2",
    "1,2,3,4",
    ",,",
    "nan,0,1",
    "1e308,1e308,1e308",
    "uint8",
    "uint16",
    "int16",
    "float32",
    "double",
    "u8",
    "1,1,1",
    "0,1,1",
    "-1,1,1",
    "1,1,nan",
    "shading",
    "shadng",
    "jitter",
    "",
    "a,b,,c",
    "longest_ray_voxels=1e300",
    "segment_steps=0",
    "segment_steps=-5",
    "segment_steps=nan",
    "step_voxels=0.5",
    "threshold=2",
    "x=",
    "=1",
    "a=b=c",
    "display",
    "image",
    "hit",
    "nope",
    "é",
    "\u{feff}",
    "\u{0}",
    "--",
    "-o",
];

const PLAN_FLAGS: &[&str] = &["--size", "--features", "--scalar"];
const RENDER_FLAGS: &[&str] = &[
    "--size",
    "--features",
    "--volume",
    "--dims",
    "--dtype",
    "--spacing",
    "--big-endian",
    "--tf",
    "--tf-map",
    "--camera",
    "--frames",
    "--output",
];
/// Flags that do not belong (or do not exist): mostly usage errors.
const STRAY_FLAGS: &[&str] = &["--help", "--bogus", "--scalar", "--volume", "-o", "--out", "--version"];

fn value() -> impl Strategy<Value = String> {
    let files = files().clone();
    prop_oneof![
        4 => proptest::sample::select(HOSTILE).prop_map(str::to_string),
        4 => proptest::sample::select(files),
        1 => "[ -~]{0,12}",
        1 => "\\PC{0,6}",
    ]
}

/// A well-formed value for `flag`, so that lines get past clap and exercise the checks behind it.
fn plausible(flag: &str) -> Vec<String> {
    let files = files();
    let pick = |needle: &str| files.iter().filter(|f| f.contains(needle)).cloned().collect::<Vec<_>>();
    let fixed = |v: &[&str]| v.iter().map(|s| s.to_string()).collect::<Vec<_>>();
    match flag {
        "--size" => fixed(&["16x16", "24x8", "8x32"]),
        "--features" => fixed(&["shading", "jitter"]),
        "--scalar" => fixed(&["segment_steps=4", "step_voxels=1", "longest_ray_voxels=40", "threshold=0.9"]),
        "--volume" => [pick(".raw"), pick(".nrrd"), pick(".nhdr"), pick(".mha")].concat(),
        "--dims" => fixed(&["4x4x4", "2x2x2"]),
        "--dtype" => fixed(&["uint8", "uint16", "int16"]),
        "--spacing" => fixed(&["1,1,2", "0.5,1,1"]),
        "--tf" => [pick(".json"), pick("tf.ron")].concat(),
        "--tf-map" => fixed(&["A", "B", "b"]),
        "--camera" => fixed(&["30,20,3.2", "0,0,0.2", "90,-90,50"]),
        "--frames" => fixed(&["1", "2"]),
        "--output" => fixed(&["image", "display"]),
        _ => fixed(&["x"]),
    }
}

fn flags(pool: &'static [&'static str]) -> impl Strategy<Value = Vec<(&'static str, String)>> {
    let flag = prop_oneof![9 => proptest::sample::select(pool), 1 => proptest::sample::select(STRAY_FLAGS)];
    let pair =
        flag.prop_flat_map(|f| (Just(f), prop_oneof![1 => proptest::sample::select(plausible(f)), 1 => value()]));
    proptest::collection::vec(pair, 0..5)
}

fn command_line() -> impl Strategy<Value = Vec<String>> {
    let graphs: Vec<String> = files().iter().filter(|f| f.ends_with(".ron")).cloned().collect();
    let outputs: Vec<String> = files().iter().filter(|f| f.contains("out")).cloned().collect();
    let plan = (Just("plan"), flags(PLAN_FLAGS), Just(None::<String>)).boxed();
    let render = (
        Just("render"),
        flags(RENDER_FLAGS),
        proptest::option::weighted(0.9, prop_oneof![4 => proptest::sample::select(outputs), 1 => value()]),
    )
        .boxed();
    let other = (proptest::sample::select(&["nope", "", "bench"][..]), flags(STRAY_FLAGS), Just(None)).boxed();
    (
        prop_oneof![8 => plan, 11 => render, 1 => other],
        proptest::option::weighted(0.95, proptest::sample::select(graphs)),
        proptest::option::weighted(0.1, value()),
    )
        .prop_map(|((sub, flags, out), graph, junk)| {
            let mut argv = vec!["volgraph".to_string(), sub.to_string()];
            argv.extend(graph);
            for (flag, v) in flags {
                argv.push(flag.to_string());
                if flag != "--big-endian" && flag != "--help" && flag != "--version" {
                    argv.push(v);
                }
            }
            if let Some(out) = out {
                argv.extend(["-o".to_string(), out]);
            }
            argv.extend(junk);
            argv
        })
}

/// What one command line gave.
#[derive(Debug, PartialEq, Eq, PartialOrd, Ord, Clone, Copy)]
enum Outcome {
    /// clap printed help or the version: exit 0.
    Help,
    /// clap rejected the line: exit 2.
    Usage,
    /// A checked input was wrong: exit 1.
    Rejected,
    /// Ready to render or printed a plan: exit 0.
    Accepted,
}

fn run_line(argv: &[String]) -> Result<Outcome, String> {
    let cli = match Cli::try_parse_from(argv) {
        Ok(cli) => cli,
        Err(e) => {
            let code = e.exit_code();
            return match e.kind() {
                clap::error::ErrorKind::DisplayHelp
                | clap::error::ErrorKind::DisplayVersion
                | clap::error::ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand
                    if code == 0 || code == 2 =>
                {
                    Ok(Outcome::Help)
                }
                _ if code == 2 => Ok(Outcome::Usage),
                _ => Err(format!("clap error with exit code {code}: {e}")),
            };
        }
    };
    match check(cli) {
        Ok(_) => Ok(Outcome::Accepted),
        Err(CliError::Graph(d)) if !d.items.is_empty() && d.to_string().starts_with(&d.file) => Ok(Outcome::Rejected),
        Err(CliError::Graph(d)) => Err(format!("graph diagnostics without a location: {d}")),
        Err(CliError::Other(e)) if !e.to_string().trim().is_empty() => Ok(Outcome::Rejected),
        Err(CliError::Other(_)) => Err("an error with an empty message".to_string()),
    }
}

#[test]
fn random_command_lines_never_panic_hang_or_exit_wrongly() {
    let run = crate::fuzz_runner::fuzz(
        &command_line(),
        cases(),
        HANG_SECONDS,
        |argv| format!("{argv:?}"),
        |argv| run_line(argv),
    );
    if let Some(failure) = run.failure {
        panic!("{failure}");
    }
    let (total, counts) = (run.total(), &run.counts);
    eprintln!(
        "cli fuzz: {total} command lines, 0 panics, 0 hangs (slowest {:.1} ms), 0 wrong exit codes; outcomes {counts:?}",
        run.slowest.as_secs_f64() * 1e3
    );
    // The fuzzer is not vacuous: it reaches both accepted and rejected inputs.
    assert!(
        total < 64 || (counts.contains_key(&Outcome::Accepted) && counts.contains_key(&Outcome::Rejected)),
        "{counts:?}"
    );
}
