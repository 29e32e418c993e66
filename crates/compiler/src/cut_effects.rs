//! A scene's crop box and clip planes as effects (`volgraph_accel::cuts`): the scene features
//! `crop` and `clip`, each the `#if` name of the same word in capitals that
//! `shaders/common/ray_box.wgsl` compiles its cut into. Unlike the DVR effects, which a graph
//! wires per pass (`"shading": "feature.shading"`), a cut belongs to the frame: every pass that
//! honours a sub-box of the volume ([`crate::decl::PassDecl::honours_volume_window`]) takes it
//! without the graph saying so, and a scene without cuts compiles none of their code.

use std::collections::BTreeSet;

use volgraph_accel::cuts::Cuts;

/// The scene feature of a crop box.
pub const CROP: &str = "crop";
/// The scene feature of clip planes.
pub const CLIP: &str = "clip";

/// (feature, `#if` name) of each cut.
const CUT_DEFINES: [(&str, &str); 2] = [(CROP, "CROP"), (CLIP, "CLIP")];

/// The scene features `cuts` turn on.
pub fn features_of(cuts: &Cuts) -> BTreeSet<String> {
    let mut out = BTreeSet::new();
    if cuts.crop().is_some() {
        out.insert(CROP.to_string());
    }
    if cuts.planes().next().is_some() {
        out.insert(CLIP.to_string());
    }
    out
}

/// The `#if` names of the cut features among `features`.
pub fn defines_of<'a>(features: impl IntoIterator<Item = &'a String>) -> Vec<&'static str> {
    let on: BTreeSet<&str> = features.into_iter().map(String::as_str).collect();
    CUT_DEFINES.iter().filter(|(feature, _)| on.contains(feature)).map(|(_, define)| *define).collect()
}

/// Whether `feature` is a cut (always known to the compiler, whatever the graph declares).
pub fn is_cut_feature(feature: &str) -> bool {
    CUT_DEFINES.iter().any(|(f, _)| *f == feature)
}
