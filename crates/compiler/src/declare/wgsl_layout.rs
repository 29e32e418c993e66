//! Uniform blocks as WGSL lays them out ([`UniformMember`]), the WGSL struct text a
//! `pass_params!` block generates, and the checks of a shader's struct against a declaration
//! (plan time and node creation).

/// A member of a uniform block as WGSL lays it out: its type's name, alignment and bytes. The
/// scalars a parameter can be (`f64` goes up as `f32`, `bool` as a `u32` 0 or 1) and vectors of
/// 2–4 `f32`, `u32` or `i32` (`[u32; 4]` is a `vec4<u32>`).
pub trait UniformMember {
    /// The WGSL type, e.g. `vec4<u32>`.
    const WGSL: &'static str;
    /// Alignment in a uniform block, in bytes.
    const ALIGN: usize;
    /// The member's bytes (little-endian), without padding.
    fn le_bytes(&self) -> Vec<u8>;
    /// Appends the member to `bytes` at its aligned offset.
    fn put(&self, bytes: &mut Vec<u8>) {
        bytes.resize(bytes.len().next_multiple_of(Self::ALIGN), 0);
        bytes.extend_from_slice(&self.le_bytes());
    }
}

macro_rules! scalar_members {
    ($($ty:ty => $wgsl:literal as $up:ty),* $(,)?) => {$(
        impl UniformMember for $ty {
            const WGSL: &'static str = $wgsl;
            const ALIGN: usize = 4;
            fn le_bytes(&self) -> Vec<u8> {
                (<$up>::from(*self)).to_le_bytes().to_vec()
            }
        }
    )*};
}

scalar_members!(f32 => "f32" as f32, u32 => "u32" as u32, i32 => "i32" as i32, bool => "u32" as u32);

impl UniformMember for f64 {
    const WGSL: &'static str = "f32";
    const ALIGN: usize = 4;
    fn le_bytes(&self) -> Vec<u8> {
        (*self as f32).to_le_bytes().to_vec()
    }
}

macro_rules! vector_members {
    ($($elem:ty, $n:literal => $wgsl:literal, $align:literal;)*) => {$(
        impl UniformMember for [$elem; $n] {
            const WGSL: &'static str = $wgsl;
            const ALIGN: usize = $align;
            fn le_bytes(&self) -> Vec<u8> {
                self.iter().flat_map(|v| v.to_le_bytes()).collect()
            }
        }
    )*};
}

vector_members! {
    f32, 2 => "vec2<f32>", 8; f32, 3 => "vec3<f32>", 16; f32, 4 => "vec4<f32>", 16;
    u32, 2 => "vec2<u32>", 8; u32, 3 => "vec3<u32>", 16; u32, 4 => "vec4<u32>", 16;
    i32, 2 => "vec2<i32>", 8; i32, 3 => "vec3<i32>", 16; i32, 4 => "vec4<i32>", 16;
}

/// The WGSL text of a parameter struct: `struct NAME { a: f32, b: u32, _pad0: f32, ... }`, each
/// member under its doc line as a comment (`docs`, one per field, or none), padded with `f32`s
/// to a multiple of 16 bytes at WGSL's uniform offsets.
pub fn wgsl_struct_text(name: &str, fields: &[(&str, &str)], docs: &[&str]) -> String {
    let mut s = format!("struct {name} {{\n");
    let mut end = 0u32;
    for (i, (field, ty)) in fields.iter().enumerate() {
        if let Some(doc) = docs.get(i) {
            s.push_str(&format!("    // {doc}\n"));
        }
        s.push_str(&format!("    {field}: {ty},\n"));
        let (align, size) = member_layout(ty).unwrap_or((4, 4));
        end = end.next_multiple_of(align) + size;
    }
    let padded = end.div_ceil(16).max(1) * 16;
    for i in 0..(padded - end) / 4 {
        s.push_str(&format!("    _pad{i}: f32,\n"));
    }
    s.push('}');
    s
}

/// Checks that the struct `name` of WGSL module `source` has exactly the fields `fields`
/// (`(name, "f32" | "u32" | "vec4<u32>" ...)`) first, in order, at WGSL's uniform offsets —
/// what a `pass_params!` struct (all scalars, 4 bytes apart) or a Rust twin uploads. Members
/// after them may only be padding (`_pad*`).
pub fn check_wgsl_struct(source: &str, name: &str, fields: &[(&str, &str)]) -> Result<(), String> {
    let module = naga::front::wgsl::parse_str(source).map_err(|e| format!("the shader does not parse: {e}"))?;
    let (handle, _) = module
        .types
        .iter()
        .find(|(_, t)| t.name.as_deref() == Some(name))
        .ok_or_else(|| format!("the shader declares no struct {name}"))?;
    check_struct_members(&module, handle, fields)
}

/// Checks the uniform blocks a shader use declares against the module: each global that the
/// module declares under a [`UniformLayout::global`] name must be a `var<uniform>` of a struct
/// with the declared members (a global the module lacks is the binding check's business: an
/// entry point that does not use it needs no buffer).
pub fn check_uniform_layouts(module: &naga::Module, uniforms: &[crate::decl::UniformLayout]) -> Result<(), String> {
    for uniform in uniforms {
        let Some((_, var)) = module.global_variables.iter().find(|(_, v)| v.name.as_deref() == Some(uniform.global))
        else {
            continue;
        };
        if var.space != naga::AddressSpace::Uniform {
            return Err(format!(
                "global \"{}\" is declared as a uniform block by the pass but the shader declares it in {:?}; \
                 declare it `var<uniform> {}: ...`",
                uniform.global, var.space, uniform.global
            ));
        }
        check_struct_members(module, var.ty, &uniform.fields)
            .map_err(|e| format!("uniform \"{}\": {e}", uniform.global))?;
    }
    Ok(())
}

/// The WGSL name of a member type the layout check describes: `f32`, `u32`, `i32` and their
/// `vec2` / `vec3` / `vec4`; `None` for anything else.
fn member_type_name(inner: &naga::TypeInner) -> Option<String> {
    let scalar = |s: &naga::Scalar| match (s.kind, s.width) {
        (naga::ScalarKind::Float, 4) => Some("f32"),
        (naga::ScalarKind::Uint, 4) => Some("u32"),
        (naga::ScalarKind::Sint, 4) => Some("i32"),
        _ => None,
    };
    match inner {
        naga::TypeInner::Scalar(s) => scalar(s).map(str::to_string),
        naga::TypeInner::Vector { size, scalar: s } => scalar(s).map(|s| format!("vec{}<{s}>", *size as u32)),
        _ => None,
    }
}

/// WGSL's (alignment, size) in a uniform block of a member type `member_type_name` names.
fn member_layout(name: &str) -> Option<(u32, u32)> {
    match name {
        "f32" | "u32" | "i32" => Some((4, 4)),
        _ => {
            let (n, rest) = name.strip_prefix("vec")?.split_at(1);
            if !matches!(rest, "<f32>" | "<u32>" | "<i32>") {
                return None;
            }
            match n {
                "2" => Some((8, 8)),
                "3" => Some((16, 12)),
                "4" => Some((16, 16)),
                _ => None,
            }
        }
    }
}

/// The members of struct type `ty` of `module` against `fields`: the same names and types, in
/// order, at the offsets WGSL's uniform layout gives them (scalars at 4, vec2 at 8, vec3 and
/// vec4 at 16 bytes); members after them may only be padding (`_pad*`).
fn check_struct_members(
    module: &naga::Module,
    ty: naga::Handle<naga::Type>,
    fields: &[(&str, &str)],
) -> Result<(), String> {
    let ty = &module.types[ty];
    let name = ty.name.as_deref().unwrap_or("the block");
    let naga::TypeInner::Struct { members, .. } = &ty.inner else {
        return Err(format!("{name} is not a struct"));
    };
    let fix = "declare the WGSL struct as the pass lays it out (#import \"params/<Struct>.wgsl\", or wgsl_struct())";
    let mut offset = 0u32;
    for (i, (field, want)) in fields.iter().enumerate() {
        let (align, size) = member_layout(want).ok_or_else(|| {
            format!("the pass declares {name} member `{field}: {want}`, a type the layout check does not describe (scalars and vectors of f32, u32, i32)")
        })?;
        offset = offset.next_multiple_of(align);
        let m = members.get(i).ok_or_else(|| format!("{name} has no member {i} ({field}: {want}); {fix}"))?;
        let got = member_type_name(&module.types[m.ty].inner).unwrap_or_else(|| "another type".to_string());
        let member = m.name.as_deref().unwrap_or("?");
        if member != *field || got != *want || m.offset != offset {
            return Err(format!(
                "{name} member {i} is `{member}: {got}` at offset {}, but the pass declares `{field}: {want}` at {offset}; {fix}",
                m.offset
            ));
        }
        offset += size;
    }
    for m in &members[fields.len()..] {
        let member = m.name.as_deref().unwrap_or("?");
        if !member.starts_with("_pad") {
            return Err(format!("{name} has a member `{member}` the pass does not declare"));
        }
    }
    Ok(())
}
