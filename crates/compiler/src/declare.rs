//! Parameters declared once: [`pass_params!`](crate::pass_params) turns one list of
//! `name: type = default, min..=max, "doc"` lines into
//! - the [`ParamSpec`](crate::ParamSpec)s the compiler checks graphs against (`specs()`),
//! - a typed Rust struct the pass reads fields of (`from_params(&Params)`: the only place names
//!   are looked up, generated from the same list, so a typo cannot compile into a silent 0.0),
//! - its GPU twin: the fields' bytes in declaration order, padded to 16 bytes for a uniform
//!   buffer (`uniform_bytes()`), and the WGSL struct text it must match (`wgsl_struct()`),
//!   which [`check_wgsl_struct`] compares with a shader's struct through naga.
//!
//! Field forms, one per line:
//! - `name: f32 = 0.5, 0.0..=1.0, "doc";` — a float parameter (`f64`: kept exact on the host,
//!   for a CPU reference, and an `f32` on the GPU; `u32` an unsigned one; `i32` an unsigned
//!   parameter a shader uses in signed arithmetic);
//! - `name: bool = false, "doc";` — a boolean parameter, a `u32` 0 or 1 on the GPU;
//! - `name: Mode = Dvr, "doc";` — a choice between the variants of a [`param_choice!`](crate::param_choice)
//!   enum (its names in the graph file), the variant's index as a `u32` on the GPU;
//! - `name: f32 = computed, "doc";` — no parameter: a number the node computes (a count derived
//!   from the volume) that still has its place in the uniform block; `from_params` sets 0.
//!   Numbers (`f32`, `u32`, `i32`) and vectors of them (`[u32; 4]` is a `vec4<u32>`, `[f32; 2]`
//!   a `vec2<f32>`): a computed flag or choice does not compile.
//!
//! The bytes follow WGSL's uniform layout ([`UniformMember`]: scalars 4 bytes apart, a `vec2`
//! aligned to 8, a `vec3` and a `vec4` to 16), so a block the node fills itself — a screen
//! rectangle, a brick pool's grid — is declared here too, its Rust struct, WGSL struct and
//! plan-time layout check from the one list.
//!
//! A block several pass kinds share (the raycasters' sampling, shading, isosurface blocks) is
//! declared once and listed whole by each kind that takes it (`[A::specs(), B::specs()].concat()`).
//! Code serving several kinds reads it with `try_from_params`: `Some` exactly when the kind
//! declares that block — a block is never declared in part, so no name is looked up by hand.

/// A choice parameter's values, declared once (see [`param_choice!`](crate::param_choice)).
pub trait ParamChoice: Copy + Sized + 'static {
    /// The names a graph file writes, in declaration order.
    const NAMES: &'static [&'static str];
    /// The values, in the same order.
    const VALUES: &'static [Self];
    /// The value a name stands for (`None` for a name not in [`Self::NAMES`]).
    fn from_name(name: &str) -> Option<Self>;
    /// The value's position in [`Self::NAMES`].
    fn index(self) -> usize;
    /// The value's name in a graph file.
    fn name(self) -> &'static str {
        Self::NAMES[self.index()]
    }
}

/// Declares the values of a choice parameter as an enum with their graph-file names, for a
/// [`pass_params!`](crate::pass_params) field:
///
/// ```
/// volgraph_compiler::param_choice! {
///     /// What the raycaster computes.
///     pub enum Mode { Dvr = "dvr", Iso = "iso" }
/// }
/// use volgraph_compiler::declare::ParamChoice;
/// assert_eq!(Mode::NAMES, ["dvr", "iso"]);
/// assert_eq!(Mode::from_name("iso"), Some(Mode::Iso));
/// assert_eq!(Mode::Iso.index(), 1);
/// ```
#[macro_export]
macro_rules! param_choice {
    (
        $(#[$meta:meta])*
        $vis:vis enum $name:ident { $( $(#[$vmeta:meta])* $variant:ident = $text:literal ),+ $(,)? }
    ) => {
        $(#[$meta])*
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
        $vis enum $name { $( $(#[$vmeta])* #[doc = concat!("`\"", $text, "\"` in a graph file.")] $variant, )+ }

        impl $crate::declare::ParamChoice for $name {
            const NAMES: &'static [&'static str] = &[$($text),+];
            const VALUES: &'static [Self] = &[$(Self::$variant),+];
            fn from_name(name: &str) -> Option<Self> {
                match name {
                    $( $text => Some(Self::$variant), )+
                    _ => None,
                }
            }
            fn index(self) -> usize {
                self as usize
            }
        }
    };
}

/// Declares a pass's parameters once (module docs). Example:
///
/// ```
/// volgraph_compiler::pass_params! {
///     /// `present`'s parameters; WGSL twin `PresentParams` in shaders/present.wgsl.
///     pub struct PresentParams {
///         background: f32 = 0.0, 0.0..=1.0, "linear grey level behind the volume";
///     }
/// }
/// let specs = PresentParams::specs();
/// assert_eq!(specs[0].name, "background");
/// assert_eq!(PresentParams::from_params(&volgraph_compiler::Params::defaults(&specs)).background, 0.0);
/// assert_eq!(PresentParams { background: 0.5 }.uniform_bytes().len(), 16);
/// ```
#[macro_export]
macro_rules! pass_params {
    (
        $(#[$meta:meta])*
        $vis:vis struct $name:ident { $($body:tt)* }
    ) => {
        $crate::pass_params!(@fields [$(#[$meta])*] [$vis] $name [] $($body)*);
    };

    // Each field line, normalized to `[field, type, form, (default), (range), doc]` (the type
    // one token tree: `f32`, `Mode` or `[u32; 4]`).
    (@fields $m:tt $v:tt $name:ident [$($done:tt)*]
        $field:ident : [$elem:ident; $n:literal] = computed, $doc:literal; $($rest:tt)*) => {
        $crate::pass_params!(@fields $m $v $name [$($done)* [$field, [$elem; $n], computed, (), (), $doc]] $($rest)*);
    };
    (@fields $m:tt $v:tt $name:ident [$($done:tt)*]
        $field:ident : bool = $d:literal, $doc:literal; $($rest:tt)*) => {
        $crate::pass_params!(@fields $m $v $name [$($done)* [$field, bool, flag, ($d), (), $doc]] $($rest)*);
    };
    (@fields $m:tt $v:tt $name:ident [$($done:tt)*]
        $field:ident : $ty:ident = computed, $doc:literal; $($rest:tt)*) => {
        $crate::pass_params!(@fields $m $v $name [$($done)* [$field, $ty, computed, (), (), $doc]] $($rest)*);
    };
    (@fields $m:tt $v:tt $name:ident [$($done:tt)*]
        $field:ident : $ty:ident = $d:literal, $lo:literal ..= $hi:literal, $doc:literal; $($rest:tt)*) => {
        $crate::pass_params!(@fields $m $v $name [$($done)* [$field, $ty, number, ($d), ($lo, $hi), $doc]] $($rest)*);
    };
    (@fields $m:tt $v:tt $name:ident [$($done:tt)*]
        $field:ident : $ty:ident = $d:ident, $doc:literal; $($rest:tt)*) => {
        $crate::pass_params!(@fields $m $v $name [$($done)* [$field, $ty, choice, ($d), (), $doc]] $($rest)*);
    };

    (@fields [$($meta:tt)*] [$vis:vis] $name:ident
        [$( [$field:ident, $ty:tt, $form:ident, $d:tt, $range:tt, $doc:literal] )*]) => {
        $($meta)*
        #[derive(Clone, Copy, Debug, PartialEq)]
        $vis struct $name {
            $( #[doc = $doc] pub $field: $ty, )*
        }

        #[allow(dead_code)] // generated API: a pass may not need every form
        impl $name {
            /// The declared parameters, for [`PassDecl::params`]($crate::PassDecl::params).
            #[allow(clippy::vec_init_then_push)] // computed fields push nothing
            pub fn specs() -> Vec<$crate::ParamSpec> {
                let mut specs = Vec::new();
                $( $crate::pass_params!(@spec specs, $form, $ty, stringify!($field), $d, $range, $doc); )*
                specs
            }

            /// The checked values of a compiled pass, typed (computed fields 0).
            pub fn from_params(p: &$crate::Params) -> Self {
                // A block of computed fields only has no parameters to read: it has its own
                // constructor, and reading it from parameters would upload zeros.
                debug_assert!(
                    !Self::specs().is_empty() || Self::wgsl_fields().is_empty(),
                    "{} declares no parameters (every field is computed): build it with its own constructor",
                    stringify!($name)
                );
                Self { $( $field: $crate::pass_params!(@get $form, $ty, p, stringify!($field)), )* }
            }

            /// This struct as a [`ParamBlock`]($crate::block::ParamBlock) a kind lists
            /// ([`PassDecl::blocks`]($crate::PassDecl::blocks)), implying no `#if` name until
            /// [`with_defines`]($crate::block::ParamBlock::with_defines) says which.
            pub fn block(on_change: $crate::block::OnChange) -> $crate::block::ParamBlock {
                $crate::block::ParamBlock { name: stringify!($name), specs: Self::specs, defines: |_| Vec::new(), on_change }
            }

            /// The block's values when the pass declares it (a block shared by several kinds
            /// is declared whole or not at all), else `None`.
            pub fn try_from_params(p: &$crate::Params) -> Option<Self> {
                Self::specs().iter().all(|s| p.declares(s.name)).then(|| Self::from_params(p))
            }

            /// The values as a uniform buffer's bytes at WGSL's offsets, zero-padded to a
            /// multiple of 16.
            pub fn uniform_bytes(&self) -> Vec<u8> {
                let mut bytes = Vec::with_capacity(16);
                $( $crate::pass_params!(@put $form, $ty, self.$field, bytes); )*
                bytes.resize(bytes.len().div_ceil(16).max(1) * 16, 0);
                bytes
            }

            /// The `(name, WGSL type)` of each member, in order.
            pub fn wgsl_fields() -> Vec<(&'static str, &'static str)> {
                vec![ $( (stringify!($field), $crate::pass_params!(@wgsl $form, $ty)), )* ]
            }

            /// Each member's doc line, in order (the comments of the generated WGSL struct).
            pub fn wgsl_docs() -> Vec<&'static str> {
                vec![ $( $doc, )* ]
            }

            /// Checks that the struct `wgsl_name` of the assembled shader `source` has these
            /// fields, in this order, at these offsets ([`check_wgsl_struct`]($crate::declare::check_wgsl_struct)).
            pub fn check_shader(source: &str, wgsl_name: &str) -> Result<(), String> {
                $crate::declare::check_wgsl_struct(source, wgsl_name, &Self::wgsl_fields())
            }

            /// The WGSL struct the shader declares for these parameters (same name, same
            /// fields in the same order, padded to 16 bytes).
            pub fn wgsl_struct() -> String {
                $crate::declare::wgsl_struct_text(stringify!($name), &Self::wgsl_fields(), &Self::wgsl_docs())
            }

            /// This block as the uniform `global` of a [`ShaderUse`]($crate::ShaderUse): the
            /// layout `volgraph plan` and node creation check the shader's struct against.
            pub fn bound_as(global: &'static str) -> $crate::decl::UniformLayout {
                Self::bound_as_with(
                    global,
                    Self::specs().iter().map(|s| s.name).collect(),
                    |p| Self::from_params(p).uniform_bytes(),
                )
            }

            /// [`Self::bound_as`] for a block whose values are computed from parameters it
            /// does not declare itself (a block of `computed` fields): `params` are the
            /// parameters `bytes` reads.
            pub fn bound_as_with(
                global: &'static str,
                params: Vec<&'static str>,
                bytes: fn(&$crate::Params) -> Vec<u8>,
            ) -> $crate::decl::UniformLayout {
                $crate::decl::UniformLayout {
                    global,
                    fields: Self::wgsl_fields(),
                    params,
                    bytes,
                    import: Self::wgsl_import,
                }
            }

            /// `(path, text)` of [`Self::wgsl_struct`] as a generated shader file, which shaders
            /// import as `#import "params/NAME.wgsl"` once it is in their sources
            /// ([`ShaderSources::with_generated`]($crate::shader_source::ShaderSources::with_generated)).
            pub fn wgsl_import() -> (String, String) {
                (format!("params/{}.wgsl", stringify!($name)), Self::wgsl_struct())
            }
        }
    };

    (@spec $v:ident, number, f32, $n:expr, ($d:literal), ($lo:literal, $hi:literal), $doc:expr) => {
        $v.push($crate::ParamSpec::float($n, $d as f64, $lo as f64, $hi as f64, $doc))
    };
    (@spec $v:ident, number, f64, $n:expr, ($d:literal), ($lo:literal, $hi:literal), $doc:expr) => {
        $v.push($crate::ParamSpec::float($n, $d as f64, $lo as f64, $hi as f64, $doc))
    };
    // A count a shader may use in signed arithmetic (loop bounds around a pixel): declared and
    // checked as an unsigned parameter, uploaded as i32.
    (@spec $v:ident, number, $ty:tt, $n:expr, ($d:literal), ($lo:literal, $hi:literal), $doc:expr) => {
        $v.push($crate::ParamSpec::uint($n, $d as u64, $lo as u64, $hi as u64, $doc))
    };
    (@spec $v:ident, flag, bool, $n:expr, ($d:literal), (), $doc:expr) => {
        $v.push($crate::ParamSpec::boolean($n, $d, $doc))
    };
    (@spec $v:ident, choice, $ty:tt, $n:expr, ($d:ident), (), $doc:expr) => {
        $v.push($crate::ParamSpec::choice(
            $n,
            $crate::declare::ParamChoice::name($ty::$d),
            <$ty as $crate::declare::ParamChoice>::NAMES,
            $doc,
        ))
    };
    (@spec $v:ident, computed, $ty:tt, $n:expr, (), (), $doc:expr) => {};

    (@get number, f32, $p:expr, $n:expr) => { $p.float($n) as f32 };
    (@get number, f64, $p:expr, $n:expr) => { $p.float($n) };
    (@get number, u32, $p:expr, $n:expr) => { $p.uint($n) as u32 };
    (@get number, i32, $p:expr, $n:expr) => { $p.uint($n) as i32 };
    (@get flag, bool, $p:expr, $n:expr) => { $p.boolean($n) };
    (@get choice, $ty:tt, $p:expr, $n:expr) => {
        // The compiler checked the name against NAMES; unchecked values read as the first.
        <$ty as $crate::declare::ParamChoice>::from_name($p.choice($n))
            .unwrap_or(<$ty as $crate::declare::ParamChoice>::VALUES[0])
    };
    (@get computed, $ty:tt, $p:expr, $n:expr) => { <$ty>::default() };

    (@put choice, $ty:tt, $e:expr, $bytes:ident) => {
        $crate::declare::UniformMember::put(&($crate::declare::ParamChoice::index($e) as u32), &mut $bytes)
    };
    (@put $form:ident, $ty:tt, $e:expr, $bytes:ident) => { $crate::declare::UniformMember::put(&$e, &mut $bytes) };

    (@wgsl choice, $ty:tt) => { "u32" };
    (@wgsl $form:ident, $ty:tt) => { <$ty as $crate::declare::UniformMember>::WGSL };
}

/// The layout half: members as WGSL lays them out, the generated struct text and the checks of a
/// shader's struct against a declaration.
mod wgsl_layout;
pub use wgsl_layout::{UniformMember, check_uniform_layouts, check_wgsl_struct, wgsl_struct_text};

#[cfg(test)]
mod tests {
    crate::pass_params! {
        /// Test parameters.
        pub struct Knobs {
            strength: f32 = 0.5, 0.0..=2.0, "how strong";
            taps: u32 = 4, 1..=16, "how many";
        }
    }

    #[test]
    fn one_declaration_gives_specs_typed_values_bytes_and_the_wgsl_struct() {
        let specs = Knobs::specs();
        assert_eq!(specs.iter().map(|s| s.name).collect::<Vec<_>>(), ["strength", "taps"]);
        let k = Knobs::from_params(&crate::Params::defaults(&specs));
        assert_eq!(k, Knobs { strength: 0.5, taps: 4 });
        let bytes = k.uniform_bytes();
        assert_eq!(bytes.len(), 16);
        assert_eq!(&bytes[4..8], &4u32.to_le_bytes());
        let wgsl = Knobs::wgsl_struct();
        assert_eq!(
            wgsl,
            "struct Knobs {\n    // how strong\n    strength: f32,\n    // how many\n    taps: u32,\n    _pad0: f32,\n    _pad1: f32,\n}"
        );
        let fields = [("strength", "f32"), ("taps", "u32")];
        assert_eq!(super::check_wgsl_struct(&wgsl, "Knobs", &fields), Ok(()));
        let swapped = "struct Knobs { taps: u32, strength: f32 }";
        let err = super::check_wgsl_struct(swapped, "Knobs", &fields).expect_err("order differs");
        assert!(err.contains("member 0 is `taps: u32`"), "{err}");
    }

    #[test]
    fn vector_members_are_checked_at_wgsl_uniform_offsets() {
        // A vec4 aligns to 16, a vec2 to 8: `size` after `rect` sits at 16, `uv` after it at 24.
        let fields = [("rect", "vec4<u32>"), ("size", "f32"), ("uv", "vec2<f32>"), ("tint", "vec3<f32>")];
        let wgsl = "struct Block { rect: vec4<u32>, size: f32, uv: vec2<f32>, tint: vec3<f32>, _pad: f32 }";
        assert_eq!(super::check_wgsl_struct(wgsl, "Block", &fields), Ok(()));
        let scalar = "struct Block { rect: vec4<f32>, size: f32, uv: vec2<f32>, tint: vec3<f32> }";
        let err = super::check_wgsl_struct(scalar, "Block", &fields).expect_err("vec4<f32> is not vec4<u32>");
        assert!(
            err.contains("member 0 is `rect: vec4<f32>` at offset 0, but the pass declares `rect: vec4<u32>`"),
            "{err}"
        );
        let moved = "struct Block { rect: vec4<u32>, uv: vec2<f32>, size: f32, tint: vec3<f32> }";
        let err = super::check_wgsl_struct(moved, "Block", &fields).expect_err("swapped");
        assert!(
            err.contains("member 1 is `uv: vec2<f32>` at offset 16, but the pass declares `size: f32` at 16"),
            "{err}"
        );
        let unknown = super::check_wgsl_struct(wgsl, "Block", &[("m", "mat4x4<f32>")]).expect_err("a matrix");
        assert!(unknown.contains("does not describe"), "{unknown}");
    }
}

#[cfg(test)]
mod vector_tests {
    crate::pass_params! {
        /// A block a node fills itself, vectors among its members.
        pub struct Screen {
            size: f32 = computed, "splat edge";
            rect: [u32; 4] = computed, "screen rectangle";
            uv: [f32; 2] = computed, "a texture coordinate";
            tint: [f32; 3] = computed, "a colour";
            gain: f32 = 1.0, 0.0..=2.0, "a parameter after them";
        }
    }

    #[test]
    fn vector_members_sit_at_wgsl_uniform_offsets_in_bytes_struct_and_layout() {
        let block = Screen { size: 2.0, rect: [1, 2, 3, 4], uv: [0.5, 0.25], tint: [1.0, 2.0, 3.0], gain: 1.5 };
        let bytes = block.uniform_bytes();
        // size 0, rect 16 (vec4 aligns to 16), uv 32, tint 48 (vec3 aligns to 16), gain 60.
        assert_eq!(bytes.len(), 64);
        assert_eq!(&bytes[0..4], &2.0f32.to_le_bytes());
        assert_eq!(&bytes[16..20], &1u32.to_le_bytes());
        assert_eq!(&bytes[28..32], &4u32.to_le_bytes());
        assert_eq!(&bytes[36..40], &0.25f32.to_le_bytes());
        assert_eq!(&bytes[56..60], &3.0f32.to_le_bytes());
        assert_eq!(&bytes[60..64], &1.5f32.to_le_bytes());
        assert_eq!(
            Screen::wgsl_fields(),
            [("size", "f32"), ("rect", "vec4<u32>"), ("uv", "vec2<f32>"), ("tint", "vec3<f32>"), ("gain", "f32")]
        );
        // The generated struct is what the layout check accepts, and naga lays it out as the bytes.
        let wgsl = Screen::wgsl_struct();
        assert_eq!(Screen::check_shader(&wgsl, "Screen"), Ok(()), "{wgsl}");
        assert!(!wgsl.contains("_pad"), "64 bytes need no padding: {wgsl}");
        assert_eq!(Screen::specs().len(), 1, "only gain is a parameter");
        let layout = Screen::bound_as("screen");
        assert_eq!((layout.import)(), ("params/Screen.wgsl".to_string(), wgsl));
    }
}

#[cfg(test)]
mod bool_tests {
    crate::pass_params! {
        /// With a flag.
        pub struct Flags {
            on: bool = true, "a switch";
            gain: f32 = 2.0, 0.0..=4.0, "a gain";
        }
    }

    #[test]
    fn a_bool_is_a_boolean_parameter_and_a_u32_on_the_gpu() {
        let specs = Flags::specs();
        assert!(matches!(specs[0].kind, crate::params::ParamKind::Bool { default: true }));
        let f = Flags::from_params(&crate::Params::defaults(&specs));
        assert_eq!(f, Flags { on: true, gain: 2.0 });
        assert_eq!(&f.uniform_bytes()[0..4], &1u32.to_le_bytes());
        assert!(Flags::wgsl_struct().contains("on: u32,"));
    }
}

#[cfg(test)]
mod choice_tests {
    use super::ParamChoice;

    crate::param_choice! {
        /// A test choice.
        pub enum Shape { Round = "round", Square = "square" }
    }

    crate::pass_params! {
        /// A choice, a computed value and a number.
        pub struct Mixed {
            shape: Shape = Square, "which shape";
            derived: f32 = computed, "set by the node";
            size: u32 = 3, 1..=9, "how big";
        }
    }

    crate::pass_params! {
        /// A block another kind might not declare.
        pub struct Other {
            gain: f32 = 1.0, 0.0..=2.0, "a gain";
        }
    }

    #[test]
    fn a_choice_is_a_typed_enum_and_its_index_on_the_gpu() {
        let specs = Mixed::specs();
        assert_eq!(specs.iter().map(|s| s.name).collect::<Vec<_>>(), ["shape", "size"], "computed is no parameter");
        assert!(matches!(
            specs[0].kind,
            crate::params::ParamKind::Choice { default: "square", options: ["round", "square"] }
        ));
        let mut params = crate::Params::defaults(&specs);
        let m = Mixed::from_params(&params);
        assert_eq!(m, Mixed { shape: Shape::Square, derived: 0.0, size: 3 });
        params.set("shape", crate::ParamValue::Choice("round".into()));
        let m = Mixed { derived: 2.5, ..Mixed::from_params(&params) };
        assert_eq!(m.shape, Shape::Round);
        let bytes = m.uniform_bytes();
        assert_eq!(&bytes[0..4], &0u32.to_le_bytes());
        assert_eq!(&bytes[4..8], &2.5f32.to_le_bytes());
        assert_eq!(Mixed::wgsl_fields(), [("shape", "u32"), ("derived", "f32"), ("size", "u32")]);
        assert_eq!(Shape::Square.name(), "square");
    }

    #[test]
    fn a_shared_block_is_read_only_where_it_is_declared() {
        let params = crate::Params::defaults(&Mixed::specs());
        assert!(Other::try_from_params(&params).is_none());
        assert!(Mixed::try_from_params(&params).is_some());
        let both = crate::Params::defaults(&[Mixed::specs(), Other::specs()].concat());
        assert_eq!(Other::try_from_params(&both), Some(Other { gain: 1.0 }));
    }
}
