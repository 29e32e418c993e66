//! Graph inputs bound by name from the command line (issue "several volumes", item 1):
//! `--volume NAME=PATH` and `--tf NAME=FILE|PRESET`, repeatable, bind the graph's inputs of that
//! name; a plain `--volume PATH` binds the one volume every volume input reads, as before. An
//! existing file whose name holds `=` is a file, not a name.

use std::path::{Path, PathBuf};

use anyhow::anyhow;
use volgraph_accel::transfer_function::TransferFunction;
use volgraph_accel::volume::Volume;
use volgraph_core::graph::ast::InputKind;

/// `NAME=PATH` split into its name and path, when `arg` is that form: the text before the
/// first `=` is a name (a letter or `_`, then letters, digits, `_`), something follows it, and
/// no file or folder is called `arg` itself.
pub fn split_named(arg: &Path) -> Option<(String, PathBuf)> {
    split_unless(arg, &|path| path.exists())
}

/// [`split_named`] with `exists` telling whether a file or folder is called `arg`.
fn split_unless(arg: &Path, exists: &dyn Fn(&Path) -> bool) -> Option<(String, PathBuf)> {
    let text = arg.to_str()?;
    let (name, rest) = text.split_once('=')?;
    let mut chars = name.chars();
    let identifier = chars.next().is_some_and(|c| c.is_ascii_alphabetic() || c == '_')
        && chars.all(|c| c.is_ascii_alphanumeric() || c == '_');
    (identifier && !rest.is_empty() && !exists(arg)).then(|| (name.to_string(), PathBuf::from(rest)))
}

/// A named volume's path and the volume of a 4D file it asks for: `cells.nii.gz#1` is volume 1
/// (from 0) of `cells.nii.gz` — a microscope's channels, bound one per input — unless a file
/// of that very name exists. `raw` comes back with that frame set.
pub fn path_and_frame(
    path: &Path,
    raw: &volgraph_accel::load::LoadOptions<'static>,
) -> (PathBuf, volgraph_accel::load::LoadOptions<'static>) {
    path_and_frame_unless(path, raw, &|p| p.exists())
}

fn path_and_frame_unless(
    path: &Path,
    raw: &volgraph_accel::load::LoadOptions<'static>,
    exists: &dyn Fn(&Path) -> bool,
) -> (PathBuf, volgraph_accel::load::LoadOptions<'static>) {
    let split = path.to_str().filter(|_| !exists(path)).and_then(|text| {
        let (file, frame) = text.rsplit_once('#')?;
        let frame: u64 = frame.parse().ok().filter(|_| frame.bytes().all(|b| b.is_ascii_digit()))?;
        (!file.is_empty()).then(|| (PathBuf::from(file), frame))
    });
    match split {
        Some((file, frame)) => (file, volgraph_accel::load::LoadOptions { frame: Some(frame), ..raw.clone() }),
        None => (path.to_path_buf(), raw.clone()),
    }
}

/// The named `--volume`s, in the order given (empty when none is named). When one is named,
/// every one must be: several plain paths are one volume's DICOM slices, which a name cannot
/// split.
pub fn named_volumes(args: &[PathBuf]) -> anyhow::Result<Vec<(String, PathBuf)>> {
    let split: Vec<Option<(String, PathBuf)>> = args.iter().map(|a| split_named(a)).collect();
    if split.iter().all(Option::is_none) {
        return Ok(Vec::new());
    }
    let mut named = Vec::new();
    for (arg, one) in args.iter().zip(split) {
        let Some((name, path)) = one else {
            return Err(anyhow!(
                "--volume {}: give every volume a name when one has one (--volume NAME=PATH, once per volume input \
                 of the graph)",
                arg.display()
            ));
        };
        if named.iter().any(|(n, _): &(String, PathBuf)| *n == name) {
            return Err(anyhow!("--volume {name}=…: the input \"{name}\" is given twice; give it once"));
        }
        named.push((name, path));
    }
    Ok(named)
}

/// The `--tf`s: the one for every transfer-function input not named (a plain `--tf`, at most
/// one) and the named ones.
pub fn split_tfs(args: &[PathBuf]) -> anyhow::Result<(Option<PathBuf>, Vec<(String, PathBuf)>)> {
    let mut plain = None;
    let mut named: Vec<(String, PathBuf)> = Vec::new();
    for arg in args {
        match split_named(arg) {
            Some((name, path)) => {
                if named.iter().any(|(n, _)| *n == name) {
                    return Err(anyhow!("--tf {name}=…: the input \"{name}\" is given twice; give it once"));
                }
                named.push((name, path));
            }
            None if plain.is_some() => {
                return Err(anyhow!(
                    "--tf is given twice without a name; give one --tf for every transfer-function input, or name \
                     each (--tf NAME=FILE|PRESET)"
                ));
            }
            None => plain = Some(arg.clone()),
        }
    }
    Ok((plain, named))
}

/// The line and column of input `name`'s declaration in a graph's `source` (its `"name":` key in
/// the `inputs:` map), for an error that points at it.
pub fn input_location(source: &str, name: &str) -> Option<(usize, usize)> {
    let inputs = source.find("inputs:")?;
    let key = format!("\"{name}\"");
    let at = inputs + source[inputs..].find(&key)?;
    let line = source[..at].matches('\n').count() + 1;
    let column = at - source[..at].rfind('\n').map_or(0, |i| i + 1) + 1;
    Some((line, column))
}

/// The volumes, transfer functions and label tables bound by name for one render: every volume
/// input of the graph named on the command line (in one frame; grids may differ, the march
/// samples each where it lies), the named transfer functions, the label tables.
pub struct NamedBindings {
    /// The input the frame's volume (the one loaded as the render's volume) is bound to, when
    /// volumes are named.
    pub primary: Option<String>,
    /// The other named volumes, `(input, volume)`, in the order given.
    pub others: Vec<(String, Volume)>,
    /// The transfer functions bound by name, or fitted to another volume (`X_tf` of `X`).
    pub tfs: Vec<NamedTf>,
    /// `(input, label table by label value)` for the graph's `LabelTable` inputs.
    pub tables: Vec<(String, Vec<[f32; 4]>)>,
    /// Volumes of different DICOM frames of reference are shown as their files place them
    /// (`--allow-frame-mismatch`) instead of refused.
    pub allow_frame_mismatch: bool,
}

/// A transfer-function input bound by name (`--tf pet_tf=hot.ron`), or one of another volume
/// (`pet_tf` of `pet`) fitted to it: what the viewer's editor of that input edits.
pub struct NamedTf {
    /// The graph input.
    pub input: String,
    /// The volume input whose values it classifies (`X` for `X_tf`); `None`: the frame volume.
    pub base: Option<String>,
    /// The transfer function.
    pub tf: TransferFunction,
    /// What `--tf NAME=` gave (a file, a preset's name); `None`: the plain `--tf` or the fit.
    pub given: Option<PathBuf>,
    /// Its LUT over the base volume's range.
    pub lut: Vec<[f32; 4]>,
}

impl NamedBindings {
    /// The volume named TF `tf` classifies: its base, else `frame`.
    pub fn base_of<'a>(&'a self, tf: &NamedTf, frame: &'a Volume) -> &'a Volume {
        tf.base.as_deref().and_then(|b| self.others.iter().find(|(n, _)| n == b)).map_or(frame, |(_, v)| v)
    }

    /// Sets the named TF `input` to `tf` (its LUT made over its base volume, `frame` where it has
    /// none); returns the LUT to upload, `None` if no such input is bound by name.
    pub fn set_tf(&mut self, input: &str, tf: TransferFunction, frame: &Volume) -> Option<&[[f32; 4]]> {
        let i = self.tfs.iter().position(|t| t.input == input)?;
        let lut = tf.to_lut_for(self.base_of(&self.tfs[i], frame), crate::inputs::LUT_SIZE);
        let named = &mut self.tfs[i];
        named.tf = tf;
        named.lut = lut;
        Some(&named.lut)
    }

    /// The index in `named` of the frame's volume: the input named `volume`, else the first.
    pub fn primary_index(named: &[(String, PathBuf)]) -> usize {
        named.iter().position(|(n, _)| n == volgraph_core::runtime::inputs::PRIMARY_VOLUME).unwrap_or(0)
    }

    /// Checks the bindings against the compiled graph's inputs (`graph` names its file in
    /// messages, `source` is its text, for the line of an input): every named input exists with
    /// the right kind, every volume input has a volume once one is named, and the volumes lie in
    /// `primary`'s frame (one march samples each where it lies). Returns warnings: volumes whose
    /// boxes do not overlap the frame volume's.
    pub fn check(
        &self,
        plan: &volgraph_core::Plan,
        graph: &str,
        source: &str,
        primary: &Volume,
    ) -> anyhow::Result<Vec<String>> {
        let of_kind = |kind: &InputKind| -> Vec<&str> {
            plan.inputs.iter().filter(|(_, k)| *k == kind).map(|(n, _)| n.as_str()).collect()
        };
        let unknown = |flag: &str, name: &str, kind: &InputKind, what: &str| {
            let known = of_kind(kind);
            let listed = if known.is_empty() {
                format!("it has no {what} input")
            } else {
                format!("its {what} inputs are: {}", known.join(", "))
            };
            anyhow!("{flag} {name}=…: graph \"{}\" has no {what} input \"{name}\"; {listed}", plan.name)
        };
        let named: Vec<&str> =
            self.primary.iter().map(String::as_str).chain(self.others.iter().map(|(n, _)| n.as_str())).collect();
        for name in &named {
            if plan.inputs.get(*name) != Some(&InputKind::Volume) {
                return Err(unknown("--volume", name, &InputKind::Volume, "volume"));
            }
        }
        for name in self.tfs.iter().map(|t| &t.input) {
            if plan.inputs.get(name) != Some(&InputKind::TransferFunction) {
                return Err(unknown("--tf", name, &InputKind::TransferFunction, "transfer-function"));
            }
        }
        let mut warnings = Vec::new();
        if let Some(first_name) = &self.primary {
            for name in of_kind(&InputKind::Volume) {
                if !named.contains(&name) {
                    let at = input_location(source, name).map_or(String::new(), |(l, c)| format!(":{l}:{c}"));
                    return Err(anyhow!(
                        "{graph}{at}: volume input \"{name}\" has nothing bound; give --volume {name}=PATH (once one \
                         volume is named, each is)"
                    ));
                }
            }
            for (name, volume) in &self.others {
                let map = volgraph_accel::fusion::TextureMap::between(primary, volume)
                    .map_err(|e| anyhow!("--volume {name}=…: {e}"))?;
                if let Err(e) = volgraph_accel::fusion::same_frame_of_reference(primary, volume) {
                    if !self.allow_frame_mismatch {
                        return Err(anyhow!("--volume {name}=…: {e}"));
                    }
                    warnings.push(format!("warning: --volume {name}=…: {e} (shown as placed: --allow-frame-mismatch)"));
                }
                // The frame volume's box in the other's texture space: disjoint from [0,1]³?
                let (a, b) = (map.apply(glam::DVec3::ZERO), map.apply(glam::DVec3::ONE));
                let (lo, hi) = (a.min(b).max(glam::DVec3::ZERO), a.max(b).min(glam::DVec3::ONE));
                if lo.cmpge(hi).any() {
                    warnings.push(format!(
                        "warning: --volume {name}=…: its box does not overlap {first_name}'s: a label map there \
                         shows nothing, a scalar volume only where it lies within {}× {first_name}'s size of \
                         it (the view is framed on {first_name}); {first_name} is {} and {name} is {}",
                        volgraph_accel::fusion::MARCH_BOX_REACH,
                        grid_text(primary),
                        grid_text(volume)
                    ));
                }
            }
        }
        Ok(warnings)
    }

    /// Binds every volume and transfer-function input of `plan`: the named ones, `volume` to the
    /// primary (or, with no volume named, to every volume input) and `lut` to a
    /// transfer-function input not named.
    pub fn bind(
        &self,
        runtime: &mut volgraph_core::runtime::Runtime,
        plan: &volgraph_core::Plan,
        volume: &Volume,
        lut: &[[f32; 4]],
    ) -> Result<(), volgraph_core::runtime::RuntimeError> {
        for (name, kind) in &plan.inputs {
            match kind {
                InputKind::Volume => match self.others.iter().find(|(n, _)| n == name) {
                    Some((_, other)) => runtime.bind_volume(name, other)?,
                    None => runtime.bind_volume(name, volume)?,
                },
                InputKind::TransferFunction => {
                    let named = self.tfs.iter().find(|t| &t.input == name).map(|t| t.lut.as_slice());
                    runtime.bind_lut(name, named.unwrap_or(lut))?
                }
                InputKind::LabelTable => match self.tables.iter().find(|(n, _)| n == name) {
                    Some((_, table)) => runtime.bind_label_table(name, table)?,
                    None => false,
                },
                InputKind::Scalar(_) | InputKind::Data(_) => false,
            };
        }
        Ok(())
    }
}

/// `N×N×N at sx × sy × sz, origin (x, y, z)` for a message about two boxes.
fn grid_text(v: &Volume) -> String {
    let origin = v.meta.origin.map_or(String::new(), |o| format!(", origin ({:.3}, {:.3}, {:.3})", o.x, o.y, o.z));
    format!("{}×{}×{} at {} × {} × {}{origin}", v.dims.x, v.dims.y, v.dims.z, v.spacing.x, v.spacing.y, v.spacing.z)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_name_is_an_identifier_before_the_first_equals_sign() {
        assert_eq!(split_named(Path::new("ct=scan.nii.gz")), Some(("ct".into(), "scan.nii.gz".into())));
        assert_eq!(split_named(Path::new("pet_1=a=b.nii")), Some(("pet_1".into(), "a=b.nii".into())));
        for plain in ["scan.nii.gz", "=x", "1ct=x", "c t=x", "ct=", "dir/ct=x"] {
            assert_eq!(split_named(Path::new(plain)), None, "{plain}");
        }
    }

    #[test]
    fn an_existing_file_whose_name_holds_an_equals_sign_is_a_file() {
        let exists = |p: &Path| p == Path::new("ct=scan.raw");
        assert_eq!(split_unless(Path::new("ct=scan.raw"), &exists), None, "the file wins");
        assert_eq!(split_unless(Path::new("ct=other.raw"), &exists), Some(("ct".into(), "other.raw".into())));
    }

    #[test]
    fn named_and_plain_volumes_and_tfs() {
        let args = |v: &[&str]| v.iter().map(PathBuf::from).collect::<Vec<_>>();
        assert!(named_volumes(&args(&["a.dcm", "b.dcm"])).expect("slices").is_empty());
        let named = named_volumes(&args(&["ct=a.nii", "labels=b.nii"])).expect("named");
        assert_eq!(named.iter().map(|(n, _)| n.as_str()).collect::<Vec<_>>(), ["ct", "labels"]);
        assert!(
            named_volumes(&args(&["ct=a.nii", "b.nii"]))
                .expect_err("mixed")
                .to_string()
                .contains("give every volume a name")
        );
        assert!(named_volumes(&args(&["ct=a", "ct=b"])).expect_err("twice").to_string().contains("given twice"));
        let (plain, named) = split_tfs(&args(&["ct-bone", "labels_tf=t.ron"])).expect("tfs");
        assert_eq!(plain, Some(PathBuf::from("ct-bone")));
        assert_eq!(named, [("labels_tf".to_string(), PathBuf::from("t.ron"))]);
        assert!(
            split_tfs(&args(&["a.ron", "b.ron"])).expect_err("two plain").to_string().contains("twice without a name")
        );
    }

    #[test]
    fn a_frame_suffix_picks_a_volume_of_a_4d_file_unless_the_file_is_so_named() {
        let raw = volgraph_accel::load::LoadOptions::default();
        let none = |_: &Path| false;
        let (file, options) = path_and_frame_unless(Path::new("cells.nii.gz#1"), &raw, &none);
        assert_eq!((file, options.frame), (PathBuf::from("cells.nii.gz"), Some(1)));
        for plain in ["cells.nii.gz", "#1", "a#b", "a#-1", "a#+1"] {
            assert_eq!(path_and_frame_unless(Path::new(plain), &raw, &none).1.frame, None, "{plain}");
        }
        let so_named = |p: &Path| p == Path::new("odd#2");
        assert_eq!(path_and_frame_unless(Path::new("odd#2"), &raw, &so_named).1.frame, None, "the file wins");
    }

    #[test]
    fn an_input_is_located_in_the_graph_text() {
        let source = "Graph(\n    name: \"x\",\n    inputs: {\n        \"volume\": Volume,\n        \"mask\": Volume,\n    },\n)";
        assert_eq!(input_location(source, "mask"), Some((5, 9)));
        assert_eq!(input_location(source, "pet"), None);
    }
}
