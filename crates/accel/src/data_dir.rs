//! Where tests and benchmarks find real data: a folder holding `volumes/` (with its
//! `MANIFEST.md`) and `tf/`. In order: the folder a program was given (`--data DIR`,
//! [`set_data_dir`]), the `VOLGRAPH_DATA` environment variable, `../shared/data` from the
//! current folder (the README's layout, commands run from the checkout), and — for tests only —
//! `<workspace root>/../shared/data` as the source tree was built. Every volgraph program calls
//! [`forget_build_path`] first (`volgraph_app::main_with`): a binary never reads data from the
//! build machine's source path.
//!
//! Datasets are named by the part of the file name before `_XxYxZ_dtype.raw`
//! (`hydrogen_atom` → `volumes/hydrogen_atom_128x128x128_uint8.raw`). Under CI (the `CI`
//! environment variable set) a missing dataset is a failure; elsewhere a test may skip it with a
//! printed note — [`require_dataset`] implements that rule once for tests and benchmarks.

use std::path::{Path, PathBuf};

use glam::DVec3;

use crate::load::{LoadError, LoadedVolume, RawOptions, load_volume, parse_raw_name};

/// The environment variable naming the data folder.
pub const DATA_ENV: &str = "VOLGRAPH_DATA";

/// Why a dataset could not be found or read.
#[derive(Debug, thiserror::Error)]
pub enum DataError {
    /// The volumes folder cannot be listed.
    #[error(
        "cannot list the volumes folder {}: {source}; give --data DIR or set {DATA_ENV} to the folder that \
         holds volumes/ (default: ../shared/data)",
        .dir.display()
    )]
    NoVolumesDir {
        /// The folder.
        dir: PathBuf,
        /// The OS error.
        source: std::io::Error,
    },
    /// No dataset has that name.
    #[error(
        "dataset \"{name}\" not found in {}; available: {}. Give --data DIR or set {DATA_ENV} to another data folder if it lives elsewhere",
        .dir.display(), if .available.is_empty() { "none".to_string() } else { .available.join(", ") }
    )]
    NotFound {
        /// The name asked for.
        name: String,
        /// The folder searched.
        dir: PathBuf,
        /// The dataset names found there.
        available: Vec<String>,
    },
    /// The name is a prefix of several datasets.
    #[error("dataset name \"{name}\" is ambiguous: it matches {}; use the full name", .matches.join(", "))]
    Ambiguous {
        /// The name asked for.
        name: String,
        /// The datasets it matches.
        matches: Vec<String>,
    },
    /// `MANIFEST.md` is missing or has no row for a file.
    #[error("{}: {message}", .path.display())]
    Manifest {
        /// The manifest file.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// The dataset's file failed to load.
    #[error(transparent)]
    Load(#[from] LoadError),
}

/// The folder `--data DIR` gave, which wins over everything else.
static GIVEN: std::sync::RwLock<Option<PathBuf>> = std::sync::RwLock::new(None);
/// Set by [`forget_build_path`].
static NO_BUILD_PATH: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

/// Makes `dir` the data folder of this process (a program's `--data DIR`).
pub fn set_data_dir(dir: PathBuf) {
    *GIVEN.write().unwrap_or_else(|e| e.into_inner()) = Some(dir);
}

/// Stops [`data_dir`] from falling back on the source tree this crate was built in: what a
/// program calls at start, so an installed binary finds data only where its user says (or in
/// `../shared/data` beside the folder it runs in).
pub fn forget_build_path() {
    NO_BUILD_PATH.store(true, std::sync::atomic::Ordering::Relaxed);
}

/// The data folder (module docs give the order).
pub fn data_dir() -> PathBuf {
    if let Some(dir) = GIVEN.read().unwrap_or_else(|e| e.into_inner()).clone() {
        return dir;
    }
    let beside = Path::new("../shared/data");
    match std::env::var_os(DATA_ENV) {
        Some(dir) if !dir.is_empty() => PathBuf::from(dir),
        _ if beside.join("volumes").is_dir() => beside.to_path_buf(),
        _ if NO_BUILD_PATH.load(std::sync::atomic::Ordering::Relaxed) => beside.to_path_buf(),
        _ => {
            let crate_dir = Path::new(env!("CARGO_MANIFEST_DIR"));
            // crates/accel → workspace root → its parent; fall back to `..` joins if the path is
            // unexpectedly shallow.
            match crate_dir.ancestors().nth(3) {
                Some(above_workspace) => above_workspace.join("shared").join("data"),
                None => crate_dir.join("../../../shared/data"),
            }
        }
    }
}

/// `data_dir()/volumes`.
pub fn volumes_dir() -> PathBuf {
    data_dir().join("volumes")
}

/// The datasets in `volumes/`: `(name, file path)` sorted by name, for every `.raw` file named
/// `name_XxYxZ_dtype.raw`.
pub fn available_datasets() -> Result<Vec<(String, PathBuf)>, DataError> {
    let dir = volumes_dir();
    let entries = std::fs::read_dir(&dir).map_err(|source| DataError::NoVolumesDir { dir: dir.clone(), source })?;
    let mut found: Vec<(String, PathBuf)> = entries
        .filter_map(|entry| entry.ok())
        .filter_map(|entry| {
            let file_name = entry.file_name().to_string_lossy().into_owned();
            if !file_name.ends_with(".raw") {
                return None;
            }
            let (name, _, _) = parse_raw_name(&file_name)?;
            Some((name, entry.path()))
        })
        .collect();
    found.sort();
    Ok(found)
}

/// The file of dataset `name`: a file's stem or name (`foo_16x16x16_uint8`), an exact dataset
/// name held by one file, or else a unique prefix of one followed by `_` (`engine` finds
/// `engine_vollib_256x256x256_uint8.raw`). Two files of one dataset name (`foo_8x8x8_uint8.raw`
/// and `foo_16x16x16_uint8.raw`) make the name ambiguous; their stems choose one.
pub fn dataset_path(name: &str) -> Result<PathBuf, DataError> {
    let all = available_datasets()?;
    let stem = |p: &Path| p.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    if let Some((_, path)) = all.iter().find(|(_, p)| stem(p) == name || p.file_name().is_some_and(|f| f == name)) {
        return Ok(path.clone());
    }
    let exact: Vec<&(String, PathBuf)> = all.iter().filter(|(n, _)| n == name).collect();
    match exact.as_slice() {
        [(_, path)] => return Ok(path.clone()),
        [] => {}
        several => {
            return Err(DataError::Ambiguous {
                name: name.to_string(),
                matches: several.iter().map(|(_, p)| stem(p)).collect(),
            });
        }
    }
    let prefix = format!("{name}_");
    let matches: Vec<&(String, PathBuf)> = all.iter().filter(|(n, _)| n.starts_with(&prefix)).collect();
    match matches.as_slice() {
        [(_, path)] => Ok(path.clone()),
        [] => Err(DataError::NotFound {
            name: name.to_string(),
            dir: volumes_dir(),
            available: all.into_iter().map(|(n, _)| n).collect(),
        }),
        several => Err(DataError::Ambiguous {
            name: name.to_string(),
            matches: several.iter().map(|(n, _)| n.clone()).collect(),
        }),
    }
}

/// True when running under CI (the `CI` environment variable is set and not empty or `false`).
pub fn is_ci() -> bool {
    std::env::var("CI").is_ok_and(|v| !v.is_empty() && v != "false" && v != "0")
}

/// For tests and benchmarks: the path of dataset `name`, or `None` (after printing a note to
/// stderr) when it is missing and we are not under CI.
///
/// # Panics
/// Under CI ([`is_ci`]) a missing dataset panics with the lookup error, so that a test cannot
/// pass by skipping its data.
#[track_caller]
pub fn require_dataset(name: &str) -> Option<PathBuf> {
    match dataset_path(name) {
        Ok(path) => Some(path),
        Err(e) if is_ci() => panic!("dataset \"{name}\" is required under CI: {e}"),
        Err(e) => {
            eprintln!("note: skipping, dataset \"{name}\" is not available: {e}");
            None
        }
    }
}

/// One row of `volumes/MANIFEST.md`.
#[derive(Clone, Debug, PartialEq)]
pub struct ManifestEntry {
    /// The file name, e.g. `neghip_64x64x64_uint8.raw`.
    pub file: String,
    /// The voxel spacing column.
    pub spacing: DVec3,
    /// The SHA-256 of the file, lowercase hex.
    pub sha256: String,
}

/// Reads the file table of `volumes/MANIFEST.md`: rows whose first cell is a back-quoted
/// `.raw` file name; the spacing and SHA-256 columns are found by header name.
pub fn read_manifest() -> Result<Vec<ManifestEntry>, DataError> {
    let path = volumes_dir().join("MANIFEST.md");
    let text = crate::input_file::read_text(&path, "data-folder manifest")
        .map_err(|e| DataError::Manifest { path: path.clone(), message: e.to_string() })?;
    parse_manifest(&path, &text)
}

fn cells(line: &str) -> Vec<&str> {
    let inner = line.trim().trim_start_matches('|').trim_end_matches('|');
    inner.split('|').map(str::trim).collect()
}

fn between_backticks(cell: &str) -> Option<&str> {
    let start = cell.find('`')? + 1;
    let len = cell[start..].find('`')?;
    Some(&cell[start..start + len])
}

fn parse_manifest(path: &Path, text: &str) -> Result<Vec<ManifestEntry>, DataError> {
    let bad = |message: String| DataError::Manifest { path: path.to_path_buf(), message };
    let mut columns: Option<(usize, usize)> = None;
    let mut entries = Vec::new();
    for line in text.lines().filter(|l| l.trim_start().starts_with('|')) {
        let row = cells(line);
        if row.first().is_some_and(|c| *c == "File") {
            let spacing = row.iter().position(|c| c.contains("spacing"));
            let sha = row.iter().position(|c| c.contains("SHA-256"));
            columns = spacing.zip(sha);
            continue;
        }
        let Some((spacing_col, sha_col)) = columns else {
            continue;
        };
        let Some(file) = row.first().and_then(|c| between_backticks(c)) else {
            continue;
        };
        if !file.ends_with(".raw") {
            continue;
        }
        let spacing: Vec<f64> = row
            .get(spacing_col)
            .map(|c| c.split(',').filter_map(|s| s.trim().parse().ok()).collect())
            .unwrap_or_default();
        let &[sx, sy, sz] = spacing.as_slice() else {
            return Err(bad(format!("the spacing of {file} is not three numbers")));
        };
        if ![sx, sy, sz].iter().all(|s| s.is_finite() && *s > 0.0) {
            return Err(bad(format!("the spacing of {file} ({sx}, {sy}, {sz}) is not three positive numbers")));
        }
        let sha256 = row
            .get(sha_col)
            .and_then(|c| between_backticks(c))
            .filter(|h| h.len() == 64 && h.bytes().all(|b| b.is_ascii_hexdigit()))
            .ok_or_else(|| bad(format!("the SHA-256 of {file} is not 64 hex digits")))?;
        entries.push(ManifestEntry {
            file: file.to_string(),
            spacing: DVec3::new(sx, sy, sz),
            sha256: sha256.to_ascii_lowercase(),
        });
    }
    if entries.is_empty() {
        return Err(bad("no file table (| File | … | Voxel spacing | … | SHA-256 |) found".to_string()));
    }
    Ok(entries)
}

/// Loads dataset `name` with the voxel spacing its manifest row gives (raw files carry none;
/// `lobster` is 1 × 1 × 1.4). Without a manifest row the spacing is (1, 1, 1).
pub fn load_dataset(name: &str) -> Result<LoadedVolume, DataError> {
    let (path, spacing) = dataset_file(name)?;
    Ok(load_volume(&path, &RawOptions { spacing, ..RawOptions::default() })?)
}

/// Dataset `name`'s file and the voxel spacing its manifest row gives (`None` without a row), for
/// a reader of its own (a sort-last rank reads only its box of the file).
pub fn dataset_file(name: &str) -> Result<(PathBuf, Option<DVec3>), DataError> {
    let path = dataset_path(name)?;
    let file_name = path.file_name().map(|f| f.to_string_lossy().into_owned()).unwrap_or_default();
    // No manifest: spacing (1, 1, 1). A manifest that is there but malformed is an error, not a
    // silent fallback (it would render a 1 × 1 × 1.4 volume squashed).
    let spacing = if volumes_dir().join("MANIFEST.md").exists() {
        read_manifest()?.into_iter().find(|r| r.file == file_name).map(|r| r.spacing)
    } else {
        None
    };
    Ok((path, spacing))
}

#[cfg(test)]
mod tests {
    use super::*;

    const HEADER: &str = "| File | Voxel spacing | SHA-256 |\n|---|---|---|\n";
    const SHA: &str = "0123456789abcdef0123456789abcdef0123456789abcdef0123456789abcdef";

    /// Issue 19: a malformed manifest was ignored (`load_dataset` fell back on spacing 1, 1, 1).
    /// Every malformed row is an error naming the file and what is wrong.
    #[test]
    fn malformed_manifest_rows_are_errors() {
        let path = Path::new("volumes/MANIFEST.md");
        let good = format!("{HEADER}| `lobster_301x324x56_uint8.raw` | 1, 1, 1.4 | `{SHA}` |\n");
        let rows = parse_manifest(path, &good).expect("a good row");
        assert_eq!(rows[0].spacing, DVec3::new(1.0, 1.0, 1.4));
        for (row, expected) in [
            (
                format!("| `a_2x2x2_uint8.raw` | 1, 1 | `{SHA}` |"),
                "the spacing of a_2x2x2_uint8.raw is not three numbers",
            ),
            (format!("| `a_2x2x2_uint8.raw` | 1, 0, -2 | `{SHA}` |"), "is not three positive numbers"),
            (
                "| `a_2x2x2_uint8.raw` | 1, 1, 1 | `abc` |".to_string(),
                "the SHA-256 of a_2x2x2_uint8.raw is not 64 hex digits",
            ),
        ] {
            let err = parse_manifest(path, &format!("{HEADER}{row}\n")).expect_err(&row).to_string();
            assert!(err.starts_with("volumes/MANIFEST.md: ") && err.contains(expected), "{row}: {err}");
        }
        let err = parse_manifest(path, "no table here").expect_err("no table").to_string();
        assert!(err.contains("no file table"), "{err}");
    }
}
