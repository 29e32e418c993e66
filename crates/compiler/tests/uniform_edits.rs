//! A parameter edit is taken in place exactly when it only changes values the declared uniform
//! blocks carry (`PassDecl::only_uniforms_change`): read off the declaration, not written by
//! hand per pass.

use volgraph_compiler::decl::ShaderUse;
use volgraph_compiler::{ParamValue, Params, PassDecl, PortKind, PortSpec, TargetFormat};

volgraph_compiler::pass_params! {
    /// A uniform block: the gain.
    pub struct Glow {
        gain: f32 = 1.0, 0.0..=4.0, "how bright";
    }
}

volgraph_compiler::pass_params! {
    /// Parameters no uniform carries: a tap count that sizes the node's work, and a switch
    /// that is an `#if`.
    pub struct Shape {
        taps: u32 = 4, 1..=16, "how many";
        fast: bool = false, "compile the fast path";
    }
}

struct GlowPass;

impl PassDecl for GlowPass {
    fn kind(&self) -> &'static str {
        "glow"
    }
    fn summary(&self) -> &'static str {
        "test pass"
    }
    fn params(&self) -> Vec<volgraph_compiler::ParamSpec> {
        [Glow::specs(), Shape::specs()].concat()
    }
    fn ports(&self, _params: &Params) -> Vec<PortSpec> {
        vec![PortSpec::write("out", PortKind::target(&[TargetFormat::Rgba16Float]))]
    }
    fn shaders(&self, _params: &Params) -> Vec<ShaderUse> {
        vec![ShaderUse::new("glow.wgsl", "cs_glow").uniform(Glow::bound_as("glow"))]
    }
    fn shader_defines(&self, params: &Params) -> Vec<&'static str> {
        if Shape::from_params(params).fast { vec!["FAST"] } else { Vec::new() }
    }
}

fn edited(name: &str, value: ParamValue) -> (Params, Params) {
    let old = Params::defaults(&GlowPass.params());
    let mut new = old.clone();
    new.set(name, value);
    (old, new)
}

#[test]
fn a_value_a_uniform_carries_is_taken_in_place() {
    let (old, new) = edited("gain", ParamValue::Float(2.5));
    assert!(GlowPass.only_uniforms_change(&old, &new));
    // And the block's bytes follow the edit.
    let layout = &GlowPass.shaders(&new)[0].uniforms[0];
    assert_eq!(layout.params, ["gain"]);
    assert_eq!(&(layout.bytes)(&new)[..4], &2.5f32.to_le_bytes());
}

#[test]
fn a_value_no_uniform_carries_or_an_if_rebuilds() {
    let (old, new) = edited("taps", ParamValue::UInt(8));
    assert!(!GlowPass.only_uniforms_change(&old, &new), "taps is in no uniform block");
    let (old, new) = edited("fast", ParamValue::Bool(true));
    assert!(!GlowPass.only_uniforms_change(&old, &new), "fast switches an #if");
    assert!(GlowPass.only_uniforms_change(&old, &old), "no edit");
}
