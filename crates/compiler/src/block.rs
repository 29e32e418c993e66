//! Blocks of settings, declared once: a [`ParamBlock`] is one `pass_params!` struct's
//! parameters, the `#if` names its values imply and what a change of them does to a built node
//! ([`OnChange`]). A kind lists the blocks it takes ([`PassDecl::blocks`](crate::PassDecl::blocks))
//! and its parameters, `#if` names and in-place rule are derived from the list
//! ([`PassDecl::params`](crate::PassDecl::params), [`PassDecl::shader_defines`](crate::PassDecl::shader_defines),
//! [`PassDecl::updates_in_place`](crate::PassDecl::updates_in_place)), so a block that implies a
//! define — the sampling block's `JITTER` — brings it to every kind that takes the block.

use crate::params::{ParamSpec, Params};

/// What a change to a block's values does to a node built with the old ones.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum OnChange {
    /// The node takes the new values in `update_params` (they travel in a uniform it rewrites):
    /// an edit in the viewer rebuilds nothing.
    InPlace,
    /// The values shape what the node built (a pipeline constant, a pool, its resources): the
    /// node is rebuilt.
    Rebuild,
}

/// One block of settings as a kind takes it (see the module docs). Made by a `pass_params!`
/// struct's `block(on_change)`; [`Self::with_defines`] adds the `#if` names it implies.
#[derive(Clone, Copy)]
pub struct ParamBlock {
    /// The struct's name (`Sampling`), for messages and tests.
    pub name: &'static str,
    /// Its parameters.
    pub specs: fn() -> Vec<ParamSpec>,
    /// The `#if` names its values imply (given the kind's whole parameters).
    pub defines: fn(&Params) -> Vec<&'static str>,
    /// What a change of its values does to a built node.
    pub on_change: OnChange,
}

impl ParamBlock {
    /// With the `#if` names `defines` implies.
    pub fn with_defines(mut self, defines: fn(&Params) -> Vec<&'static str>) -> Self {
        self.defines = defines;
        self
    }

    /// Whether any of the block's parameters differs between `old` and `new`.
    pub fn changed(&self, old: &Params, new: &Params) -> bool {
        (self.specs)().iter().any(|s| old.value(s.name) != new.value(s.name))
    }
}

impl std::fmt::Debug for ParamBlock {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ParamBlock").field("name", &self.name).field("on_change", &self.on_change).finish()
    }
}

/// The parameters of `blocks`, in order.
pub fn block_params(blocks: &[ParamBlock]) -> Vec<ParamSpec> {
    blocks.iter().flat_map(|b| (b.specs)()).collect()
}

/// The `#if` names `blocks` imply for `params`, in block order, each once.
pub fn block_defines(blocks: &[ParamBlock], params: &Params) -> Vec<&'static str> {
    let mut defines = Vec::new();
    for define in blocks.iter().flat_map(|b| (b.defines)(params)) {
        if !defines.contains(&define) {
            defines.push(define);
        }
    }
    defines
}

/// Whether no [`OnChange::Rebuild`] block of `blocks` changed from `old` to `new`.
pub fn no_rebuild_block_changed(blocks: &[ParamBlock], old: &Params, new: &Params) -> bool {
    blocks.iter().filter(|b| b.on_change == OnChange::Rebuild).all(|b| !b.changed(old, new))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ParamValue;

    crate::pass_params! {
        /// A block whose flag implies a define.
        pub struct Look {
            glow: bool = false, "glow";
            gain: f32 = 1.0, 0.0..=2.0, "gain";
        }
    }

    crate::pass_params! {
        /// A block that shapes the pipeline.
        pub struct Shape {
            lanes: u32 = 8, 1..=64, "lanes";
        }
    }

    fn blocks() -> Vec<ParamBlock> {
        vec![
            Look::block(OnChange::InPlace)
                .with_defines(|p| if Look::from_params(p).glow { vec!["GLOW"] } else { vec![] }),
            Shape::block(OnChange::Rebuild),
        ]
    }

    #[test]
    fn parameters_defines_and_the_rebuild_rule_come_from_the_blocks() {
        let blocks = blocks();
        let specs = block_params(&blocks);
        assert_eq!(specs.iter().map(|s| s.name).collect::<Vec<_>>(), ["glow", "gain", "lanes"]);
        let old = Params::defaults(&specs);
        assert!(block_defines(&blocks, &old).is_empty());
        let mut glowing = old.clone();
        glowing.set("glow", ParamValue::Bool(true));
        assert_eq!(block_defines(&blocks, &glowing), ["GLOW"]);
        let mut brighter = old.clone();
        brighter.set("gain", ParamValue::Float(1.5));
        assert!(no_rebuild_block_changed(&blocks, &old, &brighter), "gain is in place");
        let mut wider = old.clone();
        wider.set("lanes", ParamValue::UInt(16));
        assert!(!no_rebuild_block_changed(&blocks, &old, &wider), "lanes rebuild");
    }
}
