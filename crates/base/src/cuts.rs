//! Crop box and clip planes: the parts of the volume a scene cuts away (VTK's cropping region
//! and clipping planes, Slicer's ROI). A cut never moves the step grid — rays are still met with
//! the whole box and sample k lies where it lies without the cut — it only drops the samples
//! outside what the cuts keep, so a crop to half the volume renders like the volume with the
//! other half zeroed, up to the filter's reach at the cut (`docs/rendering_model.md`, "Cuts").
//!
//! The one definition of what a cut keeps: [`Cuts::keeps_interval`] here (the f64 reference) and
//! `cut_segment` in `shaders/common/ray_box.wgsl` (every GPU raycaster) compute the same
//! interval. Both live in volume fractions, `[0,1]³` across the whole volume.

use glam::DVec3;

/// The most clip planes a scene may set (the frame uniforms hold this many).
pub const MAX_CLIP_PLANES: usize = 6;

/// The largest plane offset (for a unit normal, in volume widths) a clip plane may have.
pub const MAX_PLANE_OFFSET: f64 = 1000.0;

/// How far behind a cut face its flat shading reaches, in voxels ([`Cuts::cap_normal`]).
pub const CAP_VOXELS: f64 = 2.0;

/// A box in volume fractions, `lo < hi` on every axis, inside `[0,1]³`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CropBox {
    /// The low corner (fractions of the volume per axis).
    pub lo: DVec3,
    /// The high corner.
    pub hi: DVec3,
}

/// A plane that keeps the fractions `f` with `normal · f >= offset` (the side its normal points
/// to): `normal (1,0,0), offset 0.5` keeps the half of the volume at x >= 0.5. [`Self::new`]
/// keeps the numbers as written unless the normal's largest component lies outside
/// 1e-6..1e6; such a plane is scaled to a unit normal (the same half-space), so its numbers fit
/// the f32 frame uniforms.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ClipPlane {
    /// The normal (the kept side is the one it points to).
    pub normal: DVec3,
    /// The plane's offset: `normal · f = offset` on the plane.
    pub offset: f64,
}

/// A bad crop box or clip plane, naming the number at fault.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CutError {
    /// Not the expected count of numbers.
    #[error("{what} takes {expected} comma-separated numbers ({form}), got {got}")]
    Count {
        /// The flag or field.
        what: &'static str,
        /// How many it takes.
        expected: usize,
        /// Their names, e.g. `X0,Y0,Z0,X1,Y1,Z1`.
        form: &'static str,
        /// How many were given.
        got: usize,
    },
    /// A part that is not a finite number.
    #[error("{what}: \"{text}\" (number {index} of {form}) is not a finite number")]
    NotANumber {
        /// The flag or field.
        what: &'static str,
        /// The part as written.
        text: String,
        /// Its position, from 1.
        index: usize,
        /// The numbers' names.
        form: &'static str,
    },
    /// A crop corner outside `[0,1]`, or an empty box.
    #[error(
        "crop box: on the {axis} axis it runs from {lo} to {hi}; fractions of the volume must satisfy 0 <= lo < hi <= 1"
    )]
    BadCrop {
        /// `x`, `y` or `z`.
        axis: char,
        /// The low end given.
        lo: f64,
        /// The high end given.
        hi: f64,
    },
    /// A zero normal.
    #[error("clip plane: the normal ({}, {}, {}) has no direction; give the side to keep, e.g. 1,0,0", .0[0], .0[1], .0[2])]
    ZeroNormal([f64; 3]),
    /// A plane so far from the volume that it keeps all of it or none: surely a typo.
    #[error(
        "clip plane: the offset {0:e} (for a unit normal) lies more than {MAX_PLANE_OFFSET} volume widths away; \
         planes through the volume have offsets within about ±2"
    )]
    FarPlane(f64),
    /// More planes than the frame holds.
    #[error("{0} clip planes: at most {MAX_CLIP_PLANES} are supported")]
    TooManyPlanes(usize),
}

fn numbers<const N: usize>(text: &str, what: &'static str, form: &'static str) -> Result<[f64; N], CutError> {
    let parts: Vec<&str> = text.split(',').map(str::trim).collect();
    if parts.len() != N {
        return Err(CutError::Count { what, expected: N, form, got: parts.len() });
    }
    let mut out = [0.0; N];
    for (i, part) in parts.iter().enumerate() {
        out[i] = part.parse::<f64>().ok().filter(|v| v.is_finite()).ok_or_else(|| CutError::NotANumber {
            what,
            text: part.to_string(),
            index: i + 1,
            form,
        })?;
    }
    Ok(out)
}

impl CropBox {
    /// The whole volume.
    pub const WHOLE: Self = Self { lo: DVec3::ZERO, hi: DVec3::ONE };

    /// A checked box.
    pub fn new(lo: DVec3, hi: DVec3) -> Result<Self, CutError> {
        for (axis, (l, h)) in ['x', 'y', 'z'].into_iter().zip(lo.to_array().into_iter().zip(hi.to_array())) {
            if !(l.is_finite() && h.is_finite() && 0.0 <= l && l < h && h <= 1.0) {
                return Err(CutError::BadCrop { axis, lo: l, hi: h });
            }
        }
        Ok(Self { lo, hi })
    }

    /// `X0,Y0,Z0,X1,Y1,Z1` (the `--crop` form).
    pub fn parse(text: &str) -> Result<Self, CutError> {
        let [x0, y0, z0, x1, y1, z1] = numbers::<6>(text, "--crop", "X0,Y0,Z0,X1,Y1,Z1")?;
        Self::new(DVec3::new(x0, y0, z0), DVec3::new(x1, y1, z1))
    }

    /// The fraction of the volume the box keeps.
    pub fn volume_fraction(&self) -> f64 {
        (self.hi - self.lo).element_product()
    }
}

impl ClipPlane {
    /// A checked plane (see the type for when it is rescaled).
    #[allow(clippy::neg_cmp_op_on_partial_ord, reason = "a NaN fails each test and is refused")]
    pub fn new(normal: DVec3, offset: f64) -> Result<Self, CutError> {
        if !normal.is_finite() || !offset.is_finite() {
            return Err(CutError::NotANumber {
                what: "clip plane",
                text: format!("{normal}, {offset}"),
                index: 1,
                form: "NX,NY,NZ,D",
            });
        }
        // Scaled by its largest component first, so 1e-300 or 1e300 components neither underflow
        // nor overflow on the way to a unit vector.
        let largest = normal.abs().max_element();
        if !(largest > 0.0) {
            return Err(CutError::ZeroNormal(normal.to_array()));
        }
        let scaled = normal / largest;
        let length = scaled.length();
        let unit_offset = offset / largest / length;
        if !(unit_offset.abs() <= MAX_PLANE_OFFSET) {
            return Err(CutError::FarPlane(unit_offset));
        }
        if (1e-6..=1e6).contains(&largest) {
            return Ok(Self { normal, offset });
        }
        Ok(Self { normal: scaled / length, offset: unit_offset })
    }

    /// `NX,NY,NZ,D` (the `--clip` form).
    pub fn parse(text: &str) -> Result<Self, CutError> {
        let [x, y, z, d] = numbers::<4>(text, "--clip", "NX,NY,NZ,D")?;
        Self::new(DVec3::new(x, y, z), d)
    }

    /// Whether the plane keeps fraction-space point `f`.
    pub fn keeps(&self, f: DVec3) -> bool {
        self.normal.dot(f) >= self.offset
    }
}

/// What a scene cuts away: an optional crop box and up to [`MAX_CLIP_PLANES`] clip planes; the
/// default cuts nothing. A point is kept when the box and every plane keep it.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Cuts {
    crop: Option<CropBox>,
    planes: [Option<ClipPlane>; MAX_CLIP_PLANES],
}

impl Cuts {
    /// No cut.
    pub const NONE: Self = Self { crop: None, planes: [None; MAX_CLIP_PLANES] };

    /// Checked cuts: the box and every plane are checked again here (their fields are public,
    /// a panel slider may have built them), so no unchecked number reaches the GPU.
    pub fn new(crop: Option<CropBox>, planes: &[ClipPlane]) -> Result<Self, CutError> {
        if planes.len() > MAX_CLIP_PLANES {
            return Err(CutError::TooManyPlanes(planes.len()));
        }
        let crop = crop.map(|c| CropBox::new(c.lo, c.hi)).transpose()?;
        let mut out = Self { crop, planes: [None; MAX_CLIP_PLANES] };
        for (slot, p) in out.planes.iter_mut().zip(planes) {
            *slot = Some(ClipPlane::new(p.normal, p.offset)?);
        }
        Ok(out)
    }

    /// The crop box, if any.
    pub fn crop(&self) -> Option<CropBox> {
        self.crop
    }

    /// The clip planes.
    pub fn planes(&self) -> impl Iterator<Item = &ClipPlane> + '_ {
        self.planes.iter().flatten()
    }

    /// Whether anything is cut.
    pub fn is_none(&self) -> bool {
        self.crop.is_none() && self.planes().next().is_none()
    }

    /// Whether fraction-space point `f` is kept.
    pub fn keeps(&self, f: DVec3) -> bool {
        self.crop.is_none_or(|c| f.cmpge(c.lo).all() && f.cmple(c.hi).all()) && self.planes().all(|p| p.keeps(f))
    }

    /// The part `[begin, end)` of the ray `u0 + t·d` (fraction space), `t` in `[begin, end)`,
    /// that every cut keeps: the interval is convex because the kept region is (a box and
    /// half-spaces). Empty when `begin >= end`. The WGSL twin is `cut_segment`.
    pub fn keeps_interval(&self, u0: DVec3, d: DVec3, begin: f64, end: f64) -> (f64, f64) {
        let (mut begin, mut end) = (begin, end);
        if let Some(c) = self.crop {
            let (t_in, t_out) = box_span(u0, d, c.lo, c.hi);
            begin = begin.max(t_in);
            end = end.min(t_out);
        }
        for p in self.planes() {
            let along = p.normal.dot(d);
            let at = p.normal.dot(u0);
            if along > 0.0 {
                begin = begin.max((p.offset - at) / along);
            } else if along < 0.0 {
                end = end.min((p.offset - at) / along);
            } else if at < p.offset {
                end = f64::NEG_INFINITY;
            }
        }
        (begin, end)
    }
}

impl Cuts {
    /// The shading normal at fraction-space point `f` of a ray that starts (uncut) at `start`
    /// and runs along `d` (fraction space, any length), given `n`, the world unit normal of the
    /// field's gradient there: "capping". A shaded cut face would otherwise show the gradient of
    /// the material just behind it — noise, as the material is cut, not bounded, there — so `n`
    /// is turned toward the world normal of every cut face the ray enters through (its start
    /// lies on the side the face cuts away) within [`CAP_VOXELS`] of `f`, each by
    /// `1 − distance / CAP_VOXELS` (weights scaled to sum to 1 where faces meet at an edge):
    /// continuous in `f`, so the f32 GPU and this f64 twin agree closely, and flat on the face.
    /// Crop faces on the volume's own boundary are not cuts. `dims`: voxels per axis, `half`:
    /// the box's world half extent. The headlight is two-sided (`|n·l|`), so the face normals
    /// are taken on `n`'s side. WGSL twin: `cap_normal` in `shaders/common/ray_box.wgsl`.
    #[allow(clippy::too_many_arguments, reason = "the point, its ray and the volume's scale, each needed once")]
    pub fn cap_normal(&self, f: DVec3, start: DVec3, d: DVec3, n: DVec3, dims: DVec3, half: DVec3) -> DVec3 {
        let (mut sum, mut total) = (DVec3::ZERO, 0.0);
        let mut face = |normal: DVec3, offset: f64| {
            // The ray entered the kept side through this face: it started on the side the face
            // cuts away and runs into the kept one.
            if normal.dot(d) <= 0.0 || normal.dot(start) >= offset {
                return;
            }
            let voxels = (normal.dot(f) - offset) / (normal / dims).length();
            let w = (1.0 - voxels / CAP_VOXELS).clamp(0.0, 1.0);
            if w > 0.0 {
                let world = (normal / half).normalize();
                sum += w * if world.dot(n) < 0.0 { -world } else { world };
                total += w;
            }
        };
        if let Some(c) = self.crop {
            for a in 0..3 {
                let e = DVec3::AXES[a];
                if c.lo[a] > 0.0 {
                    face(e, c.lo[a]);
                }
                if c.hi[a] < 1.0 {
                    face(-e, -c.hi[a]);
                }
            }
        }
        for p in self.planes() {
            face(p.normal, p.offset);
        }
        if total <= 0.0 {
            return n;
        }
        let scale = if total > 1.0 { 1.0 / total } else { 1.0 };
        let mixed = n * (1.0 - total * scale) + sum * scale;
        if mixed.length() > 1e-12 { mixed.normalize() } else { n }
    }
}

/// The part `[t_in, t_out]` of the line `eye + t·dir` inside the box `[lo, hi]` (empty when
/// `t_in > t_out`); an axis the line runs parallel to bounds it only when the eye is outside
/// that slab. The f64 twin of `box_span` in `shaders/common/ray_box.wgsl`.
pub fn box_span(eye: DVec3, dir: DVec3, lo: DVec3, hi: DVec3) -> (f64, f64) {
    let (mut t_in, mut t_out) = (f64::NEG_INFINITY, f64::INFINITY);
    for a in 0..3 {
        if dir[a] == 0.0 {
            if eye[a] < lo[a] || eye[a] > hi[a] {
                return (f64::INFINITY, f64::NEG_INFINITY);
            }
            continue;
        }
        let (ta, tb) = ((lo[a] - eye[a]) / dir[a], (hi[a] - eye[a]) / dir[a]);
        t_in = t_in.max(ta.min(tb));
        t_out = t_out.min(ta.max(tb));
    }
    (t_in, t_out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// On a clip plane's face the normal is the plane's; CAP_VOXELS behind it the gradient's
    /// again; in between a blend. A face the ray leaves through, and a crop face on the volume's
    /// boundary, change nothing.
    #[test]
    fn capping_turns_the_normal_to_the_face_the_ray_enters_through() {
        let (dims, half) = (DVec3::splat(100.0), DVec3::splat(1.0));
        let gradient = DVec3::new(0.0, 1.0, 0.0);
        let plane = Cuts::new(None, &[ClipPlane::new(DVec3::X, 0.5).expect("plane")]).expect("cuts");
        let (entering, start) = (DVec3::new(1.0, 0.2, 0.0), DVec3::new(0.0, 0.4, 0.5));
        let cap = |cuts: &Cuts, f: DVec3, start: DVec3, d: DVec3, n: DVec3| cuts.cap_normal(f, start, d, n, dims, half);
        let on_face = cap(&plane, DVec3::new(0.5, 0.5, 0.5), start, entering, gradient);
        assert!((on_face - DVec3::X).length() < 1e-12, "{on_face}");
        let behind = cap(&plane, DVec3::new(0.5 + 2.0 / 100.0, 0.5, 0.5), start, entering, gradient);
        assert!((behind - gradient).length() < 1e-12, "{behind}");
        let between = cap(&plane, DVec3::new(0.51, 0.5, 0.5), start, entering, gradient);
        assert!((between - DVec3::new(1.0, 1.0, 0.0).normalize()).length() < 1e-12, "halfway: {between}");
        let leaving = cap(&plane, DVec3::new(0.5, 0.5, 0.5), DVec3::new(1.0, 0.5, 0.5), -entering, gradient);
        assert_eq!(leaving, gradient);
        // A ray that starts on the kept side runs past the plane without crossing it: no face.
        let alongside = cap(&plane, DVec3::new(0.505, 0.5, 0.5), DVec3::new(0.501, 0.0, 0.5), DVec3::Y, gradient);
        assert_eq!(alongside, gradient);
        // A crop whose low x face is the volume's own face: not a cut there.
        let crop =
            Cuts::new(Some(CropBox::new(DVec3::ZERO, DVec3::new(0.5, 1.0, 1.0)).expect("box")), &[]).expect("cuts");
        assert_eq!(cap(&crop, DVec3::new(0.0, 0.5, 0.5), DVec3::new(0.0, 0.5, 0.5), DVec3::X, gradient), gradient);
        let hi_face = cap(&crop, DVec3::new(0.5, 0.5, 0.5), DVec3::new(1.0, 0.5, 0.5), -DVec3::X, gradient);
        assert!((hi_face.abs() - DVec3::X).length() < 1e-12, "the cut face at x = 0.5, seen from +x: {hi_face}");
        // Anisotropic voxels and box: the world normal of a slanted plane, on the gradient's side.
        let slanted = Cuts::new(None, &[ClipPlane::new(DVec3::new(1.0, 1.0, 0.0), 1.0).expect("plane")]).expect("cuts");
        let half = DVec3::new(1.0, 0.5, 1.0);
        let n = slanted.cap_normal(
            DVec3::new(0.5, 0.5, 0.5),
            DVec3::ZERO,
            DVec3::new(1.0, 1.0, 0.0),
            -gradient,
            dims,
            half,
        );
        assert!((n - DVec3::new(-1.0, -2.0, 0.0).normalize()).length() < 1e-12, "{n}");
    }

    #[test]
    fn parses_the_cli_forms_and_names_what_is_wrong() {
        let c = CropBox::parse("0, 0.25,0,0.5,1,1").expect("a box");
        assert_eq!(c.lo, DVec3::new(0.0, 0.25, 0.0));
        assert!((c.volume_fraction() - 0.375).abs() < 1e-12);
        let p = ClipPlane::parse("1,0,0,0.5").expect("a plane");
        assert!(p.keeps(DVec3::new(0.6, 0.0, 0.0)) && !p.keeps(DVec3::new(0.4, 0.0, 0.0)));
        let e = CropBox::parse("0,0,0,1,1").expect_err("refused").to_string();
        assert!(e.contains("6 comma-separated") && e.contains("got 5"), "{e}");
        let e = CropBox::parse("0,0,0,1,x,1").expect_err("refused").to_string();
        assert!(e.contains("\"x\"") && e.contains("number 5"), "{e}");
        let e = CropBox::parse("0.5,0,0,0.5,1,1").expect_err("refused").to_string();
        assert!(e.contains("x axis") && e.contains("0 <= lo < hi <= 1"), "{e}");
        let e = CropBox::parse("0,0,0,1,1.5,1").expect_err("refused").to_string();
        assert!(e.contains("y axis"), "{e}");
        let e = ClipPlane::parse("0,0,0,1").expect_err("refused").to_string();
        assert!(e.contains("no direction"), "{e}");
        let e = ClipPlane::parse("1,0,0,inf").expect_err("refused").to_string();
        assert!(e.contains("\"inf\""), "{e}");
        for nan in ["nan,0,0,1", "1,0,0,NaN"] {
            assert!(ClipPlane::parse(nan).is_err(), "{nan}");
        }
        // Huge and tiny normals are the same half-space as a unit one; a far offset is refused.
        let huge = ClipPlane::parse("1e39,0,0,5e38").expect("a plane");
        assert_eq!((huge.normal, huge.offset), (DVec3::X, 0.5));
        let tiny = ClipPlane::parse("0,-1e-300,0,-0.5e-300").expect("a plane");
        assert_eq!((tiny.normal, tiny.offset), (DVec3::NEG_Y, -0.5));
        let e = ClipPlane::parse("1,0,0,1e39").expect_err("refused").to_string();
        assert!(e.contains("more than 1000 volume widths"), "{e}");
        assert!(CropBox::parse("0,0,0,1e39,1,1").is_err() && CropBox::parse("-1,0,0,1,1,1").is_err());
        let seven = [p; 7];
        assert!(matches!(Cuts::new(None, &seven), Err(CutError::TooManyPlanes(7))));
    }

    proptest! {
        /// The interval is exactly where the ray's points are kept: every point strictly inside
        /// it is kept, every point outside it (by a margin) is not.
        #[test]
        fn the_interval_holds_exactly_the_kept_points(
            u0 in prop::array::uniform3(-0.5f64..1.5),
            d in prop::array::uniform3(-1.0f64..1.0),
            lo in prop::array::uniform3(0.0f64..0.45),
            size in prop::array::uniform3(0.1f64..0.55),
            n in prop::array::uniform3(-1.0f64..1.0),
            offset in -0.5f64..0.5,
            use_plane: bool,
        ) {
            let (u0, d) = (DVec3::from_array(u0), DVec3::from_array(d));
            prop_assume!(d.length() > 1e-3);
            let lo = DVec3::from_array(lo);
            let crop = CropBox::new(lo, lo + DVec3::from_array(size)).expect("in range");
            let n = DVec3::from_array(n);
            prop_assume!(n.length() > 1e-3);
            let planes: Vec<ClipPlane> = if use_plane { vec![ClipPlane::new(n, offset).expect("plane")] } else { vec![] };
            let cuts = Cuts::new(Some(crop), &planes).expect("cuts");
            let (b, e) = cuts.keeps_interval(u0, d, -4.0, 4.0);
            for i in 0..=200 {
                let t = -4.0 + 8.0 * i as f64 / 200.0;
                let kept = cuts.keeps(u0 + t * d);
                if t > b + 1e-9 && t < e - 1e-9 {
                    prop_assert!(kept, "t = {t} in ({b}, {e}) not kept");
                }
                if t < b - 1e-9 || t > e + 1e-9 {
                    prop_assert!(!kept || !(-4.0..=4.0).contains(&t), "t = {t} outside ({b}, {e}) kept");
                }
            }
        }
    }
}
