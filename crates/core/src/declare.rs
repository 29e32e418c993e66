//! Parameters declared once: [`pass_params!`](crate::pass_params) turns one list of
//! `name: type = default, min..=max, "doc"` lines into
//! - the [`ParamSpec`](crate::ParamSpec)s the compiler checks graphs against (`specs()`),
//! - a typed Rust struct the pass reads fields of (`from_params(&Params)`: the only place names
//!   are looked up, generated from the same list, so a typo cannot compile into a silent 0.0),
//! - its GPU twin: the fields' bytes in declaration order, padded to 16 bytes for a uniform
//!   buffer (`uniform_bytes()`), and the WGSL struct text it must match (`wgsl_struct()`),
//!   which [`check_wgsl_struct`] compares with a shader's struct through naga.
//!
//! Types are `f32` (a float parameter), `u32` (an unsigned one), `i32` (an unsigned parameter a
//! shader uses in signed arithmetic) and `bool` (a `u32` 0 or 1 on the GPU); all are 4 bytes
//! there, so the struct has no padding inside and its layout is the declaration order. A bool
//! is written `flag: bool = false, false..=true, "doc";` (the range is the type's).

/// Declares a pass's parameters once (module docs). Example:
///
/// ```
/// volgraph_core::pass_params! {
///     /// `present`'s parameters; WGSL twin `PresentParams` in shaders/present.wgsl.
///     pub struct PresentParams {
///         background: f32 = 0.0, 0.0..=1.0, "linear grey level behind the volume";
///     }
/// }
/// let specs = PresentParams::specs();
/// assert_eq!(specs[0].name, "background");
/// assert_eq!(PresentParams::from_params(&volgraph_core::Params::defaults(&specs)).background, 0.0);
/// assert_eq!(PresentParams { background: 0.5 }.uniform_bytes().len(), 16);
/// ```
#[macro_export]
macro_rules! pass_params {
    (
        $(#[$meta:meta])*
        $vis:vis struct $name:ident {
            $( $field:ident : $ty:ident = $default:literal, $min:literal ..= $max:literal, $doc:literal; )*
        }
    ) => {
        $(#[$meta])*
        #[derive(Clone, Copy, Debug, PartialEq)]
        $vis struct $name {
            $( #[doc = $doc] pub $field: $ty, )*
        }

        impl $name {
            /// The declared parameters, for [`PassPlugin::params`]($crate::PassPlugin::params).
            pub fn specs() -> Vec<$crate::ParamSpec> {
                vec![ $( $crate::pass_params!(@spec $ty, stringify!($field), $default, $min, $max, $doc), )* ]
            }

            /// The checked values of a compiled pass, typed.
            pub fn from_params(p: &$crate::Params) -> Self {
                Self { $( $field: $crate::pass_params!(@get $ty, p, stringify!($field)), )* }
            }

            /// The values as a uniform buffer's bytes, zero-padded to a multiple of 16.
            pub fn uniform_bytes(&self) -> Vec<u8> {
                let mut bytes = Vec::with_capacity(16);
                $( bytes.extend_from_slice(&$crate::pass_params!(@bytes $ty, self.$field)); )*
                bytes.resize(bytes.len().div_ceil(16).max(1) * 16, 0);
                bytes
            }

            /// The WGSL struct the shader declares for these parameters (same name, same
            /// fields in the same order, padded to 16 bytes).
            pub fn wgsl_struct() -> String {
                let fields: &[(&str, &str)] = &[ $( (stringify!($field), $crate::pass_params!(@wgsl $ty)), )* ];
                $crate::declare::wgsl_struct_text(stringify!($name), fields)
            }
        }
    };
    (@spec f32, $n:expr, $d:expr, $lo:expr, $hi:expr, $doc:expr) => {
        $crate::ParamSpec::float($n, $d as f64, $lo as f64, $hi as f64, $doc)
    };
    (@spec u32, $n:expr, $d:expr, $lo:expr, $hi:expr, $doc:expr) => {
        $crate::ParamSpec::uint($n, $d as u64, $lo as u64, $hi as u64, $doc)
    };
    // A count a shader uses in signed arithmetic (loop bounds around a pixel): declared and
    // checked as an unsigned parameter, uploaded as i32.
    (@spec i32, $n:expr, $d:expr, $lo:expr, $hi:expr, $doc:expr) => {
        $crate::ParamSpec::uint($n, $d as u64, $lo as u64, $hi as u64, $doc)
    };
    (@spec bool, $n:expr, $d:expr, $lo:expr, $hi:expr, $doc:expr) => {
        $crate::ParamSpec::boolean($n, $d, $doc)
    };
    (@get bool, $p:expr, $n:expr) => { $p.boolean($n) };
    (@bytes bool, $e:expr) => { u32::from($e).to_le_bytes() };
    (@bytes $ty:ident, $e:expr) => { $e.to_le_bytes() };
    (@wgsl bool) => { "u32" };
    (@wgsl $ty:ident) => { stringify!($ty) };
    (@get f32, $p:expr, $n:expr) => { $p.float($n) as f32 };
    (@get u32, $p:expr, $n:expr) => { $p.uint($n) as u32 };
    (@get i32, $p:expr, $n:expr) => { $p.uint($n) as i32 };
}

/// The WGSL text of a parameter struct: `struct NAME { a: f32, b: u32, _pad0: f32, ... }`,
/// padded to 16 bytes.
pub fn wgsl_struct_text(name: &str, fields: &[(&str, &str)]) -> String {
    let mut s = format!("struct {name} {{\n");
    for (field, ty) in fields {
        s.push_str(&format!("    {field}: {ty},\n"));
    }
    let padded = fields.len().div_ceil(4).max(1) * 4;
    for i in fields.len()..padded {
        s.push_str(&format!("    _pad{}: f32,\n", i - fields.len()));
    }
    s.push('}');
    s
}

/// Checks that the struct `name` of WGSL module `source` has exactly the fields `fields`
/// (`(name, "f32" | "u32")`) first, in order, at 4-byte offsets — what a `pass_params!`
/// struct uploads. Members after them may only be padding (`_pad*`).
pub fn check_wgsl_struct(source: &str, name: &str, fields: &[(&str, &str)]) -> Result<(), String> {
    let module = naga::front::wgsl::parse_str(source).map_err(|e| format!("the shader does not parse: {e}"))?;
    let (_, ty) = module
        .types
        .iter()
        .find(|(_, t)| t.name.as_deref() == Some(name))
        .ok_or_else(|| format!("the shader declares no struct {name}"))?;
    let naga::TypeInner::Struct { members, .. } = &ty.inner else {
        return Err(format!("{name} is not a struct"));
    };
    for (i, (field, want)) in fields.iter().enumerate() {
        let m = members.get(i).ok_or_else(|| format!("{name} has no member {i} ({field}: {want})"))?;
        let got = match &module.types[m.ty].inner {
            naga::TypeInner::Scalar(naga::Scalar { kind: naga::ScalarKind::Float, width: 4 }) => "f32",
            naga::TypeInner::Scalar(naga::Scalar { kind: naga::ScalarKind::Uint, width: 4 }) => "u32",
            naga::TypeInner::Scalar(naga::Scalar { kind: naga::ScalarKind::Sint, width: 4 }) => "i32",
            _ => "another type",
        };
        let member = m.name.as_deref().unwrap_or("?");
        if member != *field || got != *want || m.offset != 4 * i as u32 {
            return Err(format!(
                "{name} member {i} is `{member}: {got}` at offset {}, but the pass declares `{field}: {want}` at {}; \
                 declare the WGSL struct as `pass_params!` lays it out (wgsl_struct())",
                m.offset,
                4 * i
            ));
        }
    }
    for m in &members[fields.len()..] {
        let member = m.name.as_deref().unwrap_or("?");
        if !member.starts_with("_pad") {
            return Err(format!("{name} has a member `{member}` the pass does not declare"));
        }
    }
    Ok(())
}

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
        assert_eq!(wgsl, "struct Knobs {\n    strength: f32,\n    taps: u32,\n    _pad0: f32,\n    _pad1: f32,\n}");
        let fields = [("strength", "f32"), ("taps", "u32")];
        assert_eq!(super::check_wgsl_struct(&wgsl, "Knobs", &fields), Ok(()));
        let swapped = "struct Knobs { taps: u32, strength: f32 }";
        let err = super::check_wgsl_struct(swapped, "Knobs", &fields).expect_err("order differs");
        assert!(err.contains("member 0 is `taps: u32`"), "{err}");
    }
}

#[cfg(test)]
mod bool_tests {
    crate::pass_params! {
        /// With a flag.
        pub struct Flags {
            on: bool = true, false..=true, "a switch";
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
