//! A scene's crop box and clip planes as effects (`volgraph_base::cuts`): the scene features
//! `crop` and `clip`, each the `#if` name of the same word in capitals that
//! `shaders/common/ray_box.wgsl` compiles its cut into, and `CUTS` with either (code every cut
//! needs, such as capping's shading normal). Unlike the DVR effects, which a graph
//! wires per pass (`"shading": "feature.shading"`), a cut belongs to the frame: every pass that
//! takes cuts ([`crate::decl::PassDecl::takes_cuts`]) takes it without the graph saying so, and
//! a scene without cuts compiles none of their code.

use std::collections::BTreeSet;

use volgraph_base::cuts::Cuts;

use crate::decl::PassDecl;

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

/// The `#if` name compiled with any cut.
const ANY_CUT: &str = "CUTS";

/// The `#if` names of the cut features among `features`, and [`ANY_CUT`] with any of them.
pub fn defines_of<'a>(features: impl IntoIterator<Item = &'a String>) -> Vec<&'static str> {
    let on: BTreeSet<&str> = features.into_iter().map(String::as_str).collect();
    let mut defines: Vec<&'static str> =
        CUT_DEFINES.iter().filter(|(feature, _)| on.contains(feature)).map(|(_, define)| *define).collect();
    if !defines.is_empty() {
        defines.push(ANY_CUT);
    }
    defines
}

/// The `#if` name of a sort-last volume window (`shaders/common/frame.wgsl` `is_window`): the
/// third frame define beside the cuts', compiled into the same passes while a window is set
/// (`Runtime::set_volume_window`), so that no frame without one pays for its branches.
pub const WINDOW: &str = "WINDOW";

/// The frame `#if` names of a frame with the cut `features` and, when `window`, a volume window.
pub fn frame_defines<'a>(features: impl IntoIterator<Item = &'a String>, window: bool) -> Vec<&'static str> {
    let mut defines = defines_of(features);
    if window {
        defines.push(WINDOW);
    }
    defines
}

/// Whether frame `defines` cut the volume (a window alone does not: a pass that cannot cut may
/// still run; a distributed render refuses it itself).
pub fn cuts_among(defines: &[&str]) -> bool {
    defines.iter().any(|d| *d != WINDOW)
}

/// The frame `#if` names pass `decl` is compiled with when `cut_defines` are the frame's: the
/// cuts' for a pass that takes cuts, [`WINDOW`] for one that honours a sub-box of the volume,
/// none for any other (a plan with cuts and a pass that cannot take them is refused,
/// `compile::passes_that_cannot_cut`; a distributed render refuses a pass that cannot split).
/// The one rule the plan check, the runtime's node creation and the tests share.
pub fn defines_for_pass<D: PassDecl + ?Sized>(decl: &D, cut_defines: &[&'static str]) -> Vec<&'static str> {
    cut_defines
        .iter()
        .copied()
        .filter(|d| if *d == WINDOW { decl.honours_volume_window() } else { decl.takes_cuts() })
        .collect()
}

/// Whether `feature` is a cut (always known to the compiler, whatever the graph declares).
pub fn is_cut_feature(feature: &str) -> bool {
    CUT_DEFINES.iter().any(|(f, _)| *f == feature)
}
