//! The real datasets in `$VOLGRAPH_DATA/volumes` (default `<workspace>/../shared/data/volumes`)
//! are found by name, hash to the SHA-256 in their MANIFEST.md and load with the dimensions of
//! their file name. Missing data skips with a note, except under CI where it fails.

use sha2::{Digest, Sha256};
use volgraph_accel::data_dir::{
    self, DataError, available_datasets, dataset_path, is_ci, load_dataset, read_manifest, require_dataset,
};
use volgraph_accel::load::parse_raw_name;
use volgraph_accel::volume::VoxelType;

/// The manifest rows, or `None` (skip) when the data folder is absent outside CI.
fn manifest() -> Option<Vec<data_dir::ManifestEntry>> {
    match read_manifest() {
        Ok(rows) => Some(rows),
        Err(e) if is_ci() => panic!("the dataset manifest is required under CI: {e}"),
        Err(e) => {
            eprintln!("note: skipping, no dataset manifest: {e}");
            None
        }
    }
}

#[test]
fn every_manifest_file_has_its_sha256_and_loads() {
    let Some(rows) = manifest() else { return };
    assert!(rows.len() >= 7, "MANIFEST.md lists 7 files; parsed {}", rows.len());
    for row in &rows {
        let (name, dims, token) =
            parse_raw_name(&row.file).unwrap_or_else(|| panic!("{} breaks the name convention", row.file));
        let Some(path) = require_dataset(&name) else {
            continue;
        };
        assert_eq!(path.file_name().and_then(|f| f.to_str()), Some(row.file.as_str()));
        let bytes = std::fs::read(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        let digest: String = Sha256::digest(&bytes).iter().map(|b| format!("{b:02x}")).collect();
        assert_eq!(digest, row.sha256, "{}", row.file);

        let loaded = load_dataset(&name).unwrap_or_else(|e| panic!("{e}"));
        let v = &loaded.volume;
        assert_eq!([v.dims.x as u64, v.dims.y as u64, v.dims.z as u64], dims, "{}", row.file);
        assert_eq!(v.data.voxel_type(), VoxelType::from_name(token.as_deref().unwrap_or("")).expect("known type"));
        assert_eq!(v.voxel_count(), bytes.len(), "uint8: one byte per voxel");
        assert_eq!(v.spacing, row.spacing, "{}: spacing from the manifest", row.file);
        assert_eq!(v.name, name);
    }
}

#[test]
fn lobster_spacing_comes_from_the_manifest() {
    let Some(_) = require_dataset("lobster") else {
        return;
    };
    let lobster = load_dataset("lobster").expect("load lobster");
    assert_eq!(lobster.volume.spacing, glam::DVec3::new(1.0, 1.0, 1.4));
}

#[test]
fn datasets_are_found_by_name_or_unique_prefix() {
    let Some(path) = require_dataset("hydrogen_atom") else {
        return;
    };
    assert!(path.ends_with("volumes/hydrogen_atom_128x128x128_uint8.raw"), "{}", path.display());
    let engine = dataset_path("engine").expect("`engine` is a unique prefix of engine_vollib");
    assert!(engine.ends_with("volumes/engine_vollib_256x256x256_uint8.raw"));
    let names: Vec<String> = available_datasets().expect("list").into_iter().map(|(n, _)| n).collect();
    match dataset_path("skull") {
        Err(DataError::NotFound { available, .. }) => assert_eq!(available, names),
        other => panic!("skull is not in the data folder, got {other:?}"),
    }
    let message = dataset_path("skull").expect_err("missing").to_string();
    assert!(message.starts_with("dataset \"skull\" not found in ") && message.contains(&names.join(", ")), "{message}");
}
