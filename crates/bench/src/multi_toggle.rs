//! `bench multi`'s label toggle as the viewer does it: through the viewer's own session
//! (`LiveSession`, no window) on the files a user would open — the CT and its label map as
//! MetaImage files, the label table as an ITK-SNAP file — and with the viewer's level of detail
//! (`view/lod.rs`): a label shown, hidden or faded counts as motion (`view/window.rs`), as a TF
//! point dragged does, so the frame that first shows it is a coarse one, and the full image
//! follows once input has rested.

use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

use anyhow::{Context as _, anyhow};
use volgraph_accel::camera::OrbitCamera;
use volgraph_accel::labels::LabelTable;
use volgraph_accel::volume::{Volume, VoxelData};
use volgraph_app::view::label_list::{LabelEdit, LabelList};
use volgraph_app::view::lod::Lod;
use volgraph_app::view::session::{LiveSession, SessionArgs};
use volgraph_core::runtime::Gpu;

use crate::graphs::measure::median;

/// What the toggle cost in the viewer's session, ms (medians).
#[derive(Clone, Debug, serde::Serialize)]
pub struct ViewerToggle {
    /// A steady full-resolution frame.
    pub full_ms: f64,
    /// From a toggle at rest (the full image on screen) to the first frame showing it finished:
    /// the table uploaded, the viewport and step switched to the level of detail's, the frame.
    pub from_rest_ms: f64,
    /// From a toggle while the coarse image is already on screen (toggles in quick succession)
    /// to its frame finished.
    pub while_coarse_ms: f64,
    /// From input at rest to the full image finished (the viewport and step restored, a frame).
    pub refined_ms: f64,
    /// The coarse image's scale per axis.
    pub scale: f64,
    /// The coarse image's step factor.
    pub step: f64,
}

/// Times label 1's visibility toggled `frames` times in the viewer's session of
/// `multi/ct_with_labels` on `ct` and `labels` (table `table`) at `viewport`, seen by `camera`.
pub fn time_in_viewer(
    gpu: &Arc<Gpu>,
    (ct, labels, table): (&Volume, &Volume, &LabelTable),
    viewport: (u32, u32),
    camera: &OrbitCamera,
    frames: u32,
) -> anyhow::Result<ViewerToggle> {
    let dir = tempfile::tempdir().context("a scratch folder for the toggle's files")?;
    let (ct_path, labels_path, table_path) =
        (dir.path().join("ct.mha"), dir.path().join("labels.mha"), dir.path().join("labels.txt"));
    write_metaimage(&ct_path, ct)?;
    write_metaimage(&labels_path, labels)?;
    let list = LabelList::of(labels, table).map_err(|e| anyhow!("{e}"))?;
    std::fs::write(&table_path, list.itk_snap_text()).context("writing the label table")?;
    let args = SessionArgs {
        // As `view --volume volume=ct.mha --volume labels=labels.mha` gives them.
        named: vec![("volume".to_string(), ct_path.clone()), ("labels".to_string(), labels_path)],
        named_tfs: vec![("tf".to_string(), PathBuf::from("ct-soft-tissue")), ("label_table".to_string(), table_path)],
        ..crate::workbench::session_args(PathBuf::from("multi/ct_with_labels"), &ct_path, viewport)
    };
    let (mut session, _) =
        LiveSession::open(gpu.clone(), &args).map_err(|e| anyhow!("{}", volgraph_app::cli::error_text(&e)))?;
    let mut frame = |session: &mut LiveSession| -> anyhow::Result<()> {
        session.frame(camera, None).map_err(|e| anyhow!(e))?;
        session.runtime.finish();
        Ok(())
    };
    let timed = |session: &mut LiveSession, frame: &mut dyn FnMut(&mut LiveSession) -> anyhow::Result<()>| {
        let t0 = Instant::now();
        frame(session).map(|_| t0.elapsed().as_secs_f64() * 1e3)
    };
    frame(&mut session)?;
    let full: Vec<f64> = (0..frames).map(|_| timed(&mut session, &mut frame)).collect::<anyhow::Result<_>>()?;
    let full_ms = median(&full);
    let mut lod = Lod::default();
    lod.observe(0, full_ms);
    let edit = |session: &mut LiveSession, k: u32| -> anyhow::Result<()> {
        let events = session.edit_labels(&LabelEdit::Visible(1, k % 2 == 1));
        match events.iter().find(|e| matches!(e, volgraph_app::view::session::Event::Error { .. })) {
            Some(e) => Err(anyhow!("label toggle: {e}")),
            None => Ok(()),
        }
    };
    // What the window does before each frame (`FramePolicy::apply_lod`): the level of detail's
    // viewport and step on the session. Returns (scale, step).
    let apply_lod = |session: &mut LiveSession, lod: &mut Lod| -> (f64, f64) {
        let want = lod.viewport(viewport);
        session.resize(want.0, want.1);
        while !session.set_step_factor(lod.step_factor()) && lod.step_factor() > 1.0 {
            lod.refuse_step();
        }
        (want.0 as f64 / viewport.0 as f64, session.step_factor())
    };
    let (mut from_rest, mut while_coarse, mut refined) = (Vec::new(), Vec::new(), Vec::new());
    let (mut scale, mut step) = (1.0, 1.0);
    for k in 0..frames {
        // At rest: the full image on screen.
        let t0 = Instant::now();
        edit(&mut session, k)?;
        lod.moved();
        (scale, step) = apply_lod(&mut session, &mut lod);
        frame(&mut session)?;
        from_rest.push(t0.elapsed().as_secs_f64() * 1e3);
        // The toggle back at once: the coarse image is on screen. (Each state, label 1 shown
        // and hidden, is timed as often in both cases.)
        let t0 = Instant::now();
        edit(&mut session, k + 1)?;
        lod.moved();
        apply_lod(&mut session, &mut lod);
        frame(&mut session)?;
        while_coarse.push(t0.elapsed().as_secs_f64() * 1e3);
        // Input rests: the full image comes back (the rest itself not counted).
        lod.moved_at(Instant::now() - std::time::Duration::from_secs(1));
        let t0 = Instant::now();
        apply_lod(&mut session, &mut lod);
        frame(&mut session)?;
        refined.push(t0.elapsed().as_secs_f64() * 1e3);
    }
    Ok(ViewerToggle {
        full_ms,
        from_rest_ms: median(&from_rest),
        while_coarse_ms: median(&while_coarse),
        refined_ms: median(&refined),
        scale,
        step,
    })
}

/// `volume` as a MetaImage file (`.mha`, the header and the voxels in one file), its spacing and
/// origin kept: what a user's scan and segmentation files carry.
fn write_metaimage(path: &Path, volume: &Volume) -> anyhow::Result<()> {
    let (kind, bytes): (&str, Vec<u8>) = match &volume.data {
        VoxelData::U8(v) => ("MET_UCHAR", v.clone()),
        VoxelData::U16(v) => ("MET_USHORT", v.iter().flat_map(|x| x.to_le_bytes()).collect()),
        VoxelData::I16(v) => ("MET_SHORT", v.iter().flat_map(|x| x.to_le_bytes()).collect()),
        VoxelData::F32(v) => ("MET_FLOAT", v.iter().flat_map(|x| x.to_le_bytes()).collect()),
    };
    let (d, s) = (volume.dims, volume.spacing);
    let o = volume.meta.origin.unwrap_or_default();
    let header = format!(
        "ObjectType = Image\nNDims = 3\nBinaryData = True\nBinaryDataByteOrderMSB = False\nDimSize = {} {} {}\n\
         ElementSpacing = {} {} {}\nOffset = {} {} {}\nElementType = {kind}\nElementDataFile = LOCAL\n",
        d.x, d.y, d.z, s.x, s.y, s.z, o.x, o.y, o.z
    );
    let mut file = std::fs::File::create(path).with_context(|| format!("creating {}", path.display()))?;
    file.write_all(header.as_bytes())
        .and_then(|_| file.write_all(&bytes))
        .with_context(|| format!("writing {}", path.display()))
}
