//! The viewer window: winit, a wgpu surface the runtime presents the graph output onto
//! (sRGB-correct), and the egui overlay drawn on top. Frames render continuously; between
//! frames the watcher's debounced file changes and the script lines from stdin are applied.

use std::path::PathBuf;
use std::sync::Arc;
use std::sync::mpsc::Receiver;

use volgraph_core::runtime::{Gpu, GpuOptions, PresentTarget};
use winit::application::ApplicationHandler;
use winit::dpi::PhysicalSize;
use winit::event::{ElementState, MouseButton, MouseScrollDelta, WindowEvent};
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop};
use winit::keyboard::{Key, ModifiersState, NamedKey};
use winit::window::{Window, WindowId};

use super::orbit::Orbit;
use super::panel::{self, Action, Timings};
use super::script::ScriptCommand;
use super::session::{Event, LiveSession, SessionArgs};
use super::slice_panes::FourUp;
use super::tf_editor::TfAction;
use super::watch::FileWatch;
use super::workbench::FramePolicy;
use super::{ViewOptions, emit};

struct Gfx {
    window: Arc<Window>,
    surface: wgpu::Surface<'static>,
    config: wgpu::SurfaceConfiguration,
    gpu: Arc<Gpu>,
    egui: egui_winit::State,
    renderer: egui_wgpu::Renderer,
}

/// The viewer's state across the event loop.
pub struct Viewer {
    session_args: SessionArgs,
    view: ViewOptions,
    script: Option<Receiver<String>>,
    gfx: Option<Gfx>,
    session: Option<LiveSession>,
    orbit: Orbit,
    watch: Option<FileWatch>,
    timings: Timings,
    modifiers: ModifiersState,
    panel_open: bool,
    /// The panel's width as last drawn, physical pixels (0 while it is closed): the image is
    /// drawn beside it, in the rest of the window, never under it.
    panel_px: u32,
    /// The pointer's last position in the window (physical pixels), for "under the cursor".
    cursor: Option<(f64, f64)>,
    /// Coarser frames while the camera moves, and when to measure the view's accuracy.
    frames: FramePolicy,
    /// The view's error against the converged reference, measured once it rests.
    accuracy: super::accuracy::LiveAccuracy,
    /// The slice pane a left-button drag moves the crosshair in.
    slice_drag: Option<volgraph_accel::reslice::SliceAxis>,
    /// Screenshots asked for since the last frame, each written (in order) after it.
    screenshots_now: Vec<PathBuf>,
    quit: bool,
    /// The outcome: an error ends the program with status 1.
    pub failure: Option<String>,
}

impl Viewer {
    fn new(session_args: SessionArgs, view: ViewOptions, script: Option<Receiver<String>>) -> Self {
        let orbit = Orbit::new(view.camera);
        Self {
            panel_open: view.panel,
            // Until the panel is first drawn: its default width (320 points) at one pixel a point.
            panel_px: if view.panel { 320 } else { 0 },
            session_args,
            view,
            script,
            gfx: None,
            session: None,
            orbit,
            watch: None,
            timings: Timings::default(),
            modifiers: ModifiersState::empty(),
            cursor: None,
            frames: FramePolicy::default(),
            accuracy: Default::default(),
            slice_drag: None,
            screenshots_now: Vec::new(),
            quit: false,
            failure: None,
        }
    }

    fn fail(&mut self, event_loop: &ActiveEventLoop, message: String) {
        self.failure = Some(message);
        event_loop.exit();
    }

    fn start(&mut self, event_loop: &ActiveEventLoop) -> Result<(), String> {
        let (w, h) = self.session_args.viewport;
        let attributes =
            Window::default_attributes().with_title("volgraph view").with_inner_size(PhysicalSize::new(w, h));
        let window = Arc::new(event_loop.create_window(attributes).map_err(|e| format!("cannot open a window: {e}"))?);
        let mut desc = wgpu::InstanceDescriptor::new_without_display_handle_from_env();
        if std::env::var_os("WGPU_BACKEND").is_none() {
            desc.backends = wgpu::Backends::VULKAN | wgpu::Backends::METAL | wgpu::Backends::DX12;
        }
        let instance = wgpu::Instance::new(desc);
        let surface =
            instance.create_surface(window.clone()).map_err(|e| format!("cannot draw into the window: {e}"))?;
        let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
            power_preference: wgpu::PowerPreference::HighPerformance,
            compatible_surface: Some(&surface),
            ..Default::default()
        }))
        .map_err(|e| format!("no GPU adapter can draw into the window ({e})"))?;
        let gpu = Arc::new(Gpu::from_adapter(&adapter, &GpuOptions::default()).map_err(|e| e.to_string())?);
        let caps = surface.get_capabilities(&adapter);
        let format = caps.formats.iter().copied().find(wgpu::TextureFormat::is_srgb).or(caps.formats.first().copied());
        let Some(format) = format else { return Err("the window surface offers no format".to_string()) };
        let size = window.inner_size();
        let mut config = surface
            .get_default_config(&adapter, size.width.max(1), size.height.max(1))
            .ok_or("the window surface is not supported by the adapter")?;
        config.format = format;
        config.present_mode = wgpu::PresentMode::AutoNoVsync;
        surface.configure(&gpu.device, &config);
        let (session, loaded) = LiveSession::open(
            gpu.clone(),
            &SessionArgs { viewport: (config.width, config.height), ..self.session_args.clone() },
        )
        .map_err(|e| match e {
            crate::cli::CliError::Graph(d) => d.to_string(),
            crate::cli::CliError::Other(e) => format!("{e:#}"),
        })?;
        let ctx = egui::Context::default();
        let egui = egui_winit::State::new(
            ctx,
            egui::ViewportId::ROOT,
            &window,
            Some(window.scale_factor() as f32),
            None,
            None,
        );
        let renderer = egui_wgpu::Renderer::new(&gpu.device, format, egui_wgpu::RendererOptions::default());
        let mut watch = FileWatch::new().map_err(|e| format!("cannot watch files: {e}"))?;
        watch.set_files(&session.watched_files());
        self.watch = Some(watch);
        // The camera for this volume: `--view` needs the patient frame; a volume in it opens
        // from the front, superior up, when nothing chose the camera (as `render` does).
        crate::scene_args::check_view_frame(self.view.patient_view.as_deref(), session.volume())
            .map_err(|e| format!("{e:#}"))?;
        if self.view.camera_is_default && session.in_patient_frame() {
            let anterior = volgraph_accel::camera::PatientView::Anterior.camera(self.view.camera.distance);
            self.orbit = Orbit::new(anterior);
        }
        let mut session = session;
        let slice_events = if self.view.slices { session.set_slice_panes(true) } else { Vec::new() };
        self.session = Some(session);
        self.gfx = Some(Gfx { window, surface, config, gpu, egui, renderer });
        self.handle(slice_events);
        // Only now: an edit made as soon as this line appears is seen by the watcher.
        emit(&loaded);
        Ok(())
    }

    fn handle(&mut self, events: Vec<Event>) {
        if !events.is_empty() {
            self.frames.changed();
        }
        for e in &events {
            emit(e);
            if let Event::Error { message, .. } | Event::NotSaved { message, .. } = e {
                crate::stdout::eprintln_escaped!("{message}");
            }
        }
        if !events.is_empty()
            && let (Some(watch), Some(session)) = (self.watch.as_mut(), self.session.as_ref())
        {
            watch.set_files(&session.watched_files());
        }
    }

    fn apply_actions(&mut self, actions: Vec<Action>) {
        if !actions.is_empty() {
            self.frames.changed();
        }
        for action in actions {
            let Some(session) = self.session.as_mut() else { return };
            let events = match action {
                Action::Param(pass, param, value) => session.set_param(&pass, &param, value),
                Action::Scalar(name, value) => session.set_scalar(&name, value),
                Action::Feature(name, on) => session.set_feature(&name, on),
                Action::Cuts(cuts) => session.set_cuts(cuts),
                Action::Lights(lights) => {
                    session.runtime.set_lights(lights);
                    Vec::new()
                }
                Action::Labels(edit) => {
                    // A label shown, hidden or faded changes the picture as a TF edit does:
                    // coarse frames until input rests, so the change shows at once.
                    if edit != crate::view::label_list::LabelEdit::Save {
                        self.frames.moved();
                    }
                    session.edit_labels(&edit)
                }
                Action::LabelSearch(text) => {
                    session.set_label_search(text);
                    Vec::new()
                }
                Action::Assign(text) => session.assign(&text),
                Action::TimeEachPass(on) => {
                    session.runtime.set_step_profiling(on);
                    Vec::new()
                }
                Action::SlicePanes(open) => session.set_slice_panes(open),
                Action::SlicePlanesIn3d(on) => {
                    if let Some(panes) = session.slices_mut() {
                        panes.planes_in_3d = on;
                    }
                    Vec::new()
                }
                Action::SliceWindow(window) => {
                    if let Some(panes) = session.slices_mut() {
                        panes.view.window = window;
                    }
                    Vec::new()
                }
                Action::Lod { enabled, target_fps } => {
                    self.frames.set_lod(enabled, target_fps);
                    Vec::new()
                }
                Action::TransferFunction(TfAction::Edit(tf)) => {
                    // A point dragged in the editor is motion too: coarse frames until it rests.
                    self.frames.moved();
                    session.edit_transfer_function(tf)
                }
                Action::TransferFunction(TfAction::Save) => session.save_transfer_function_events(),
                Action::TfTarget(target) => {
                    session.workbench_mut().tf_target = target;
                    Vec::new()
                }
                Action::TransferFunction(TfAction::SaveOnChange(on)) => {
                    session.workbench_mut().edited_tf_mut().save_on_change = on;
                    Vec::new()
                }
                Action::SaveScene(path) => {
                    // The image as the window shows it (beside the panel), which the screenshot
                    // saves too: `render --scene` draws the same picture.
                    let (panel_px, slices) = (self.panel_px, session.slices().is_some());
                    let window = self.gfx.as_ref().map_or(session.options().viewport, |g| {
                        view_size((g.config.width, g.config.height), panel_px, slices)
                    });
                    match session.save_view(&self.orbit.camera, window, &path) {
                        Ok(tf_file) => {
                            crate::stdout::println_escaped!("saved scene {}", path.display());
                            if let Some(tf) = tf_file {
                                crate::stdout::println_escaped!(
                                    "saved transfer function {} (the edited one on screen, which the scene reads){}",
                                    tf.path.display(),
                                    if tf.replaced {
                                        "; it replaced the file of that name, this scene name's own TF from an earlier save"
                                    } else {
                                        ""
                                    }
                                );
                            }
                            Vec::new()
                        }
                        Err(e) => {
                            vec![super::session::Event::NotSaved {
                                what: "view".to_string(),
                                message: format!("{e:#}"),
                            }]
                        }
                    }
                }
                Action::SaveImage { path, size } => match session.save_image(&self.orbit.camera, size, &path) {
                    Ok(()) => {
                        crate::stdout::println_escaped!("saved image {} ({}x{})", path.display(), size.0, size.1);
                        Vec::new()
                    }
                    Err(e) => {
                        vec![super::session::Event::NotSaved { what: "image".to_string(), message: format!("{e:#}") }]
                    }
                },
                Action::Screenshot => {
                    self.screenshots_now
                        .push(self.view.screenshot.clone().unwrap_or_else(|| PathBuf::from("volgraph.png")));
                    Vec::new()
                }
                Action::ResetCamera => {
                    self.orbit.reset();
                    Vec::new()
                }
                Action::PatientView(view) => {
                    self.orbit.camera = volgraph_accel::camera::OrbitCamera {
                        target: self.orbit.camera.target,
                        ..view.camera(self.orbit.camera.distance)
                    };
                    if !session.in_patient_frame() {
                        crate::stdout::eprintln_escaped!(
                            "note: the {view:?} view names a patient side, but this volume lies in index axes (+z up, \
                             seen from -y)"
                        );
                    }
                    Vec::new()
                }
                Action::WriteBack => match session.write_back() {
                    Ok(lines) => {
                        for line in lines {
                            crate::stdout::println_escaped!("wrote {line}");
                        }
                        Vec::new()
                    }
                    Err(e) => vec![super::session::Event::NotSaved {
                        what: "values to the graph file".to_string(),
                        message: format!("{e:#}"),
                    }],
                },
            };
            self.handle(events);
        }
    }

    /// Script lines from stdin: `quit`, `screenshot PATH`, `param PASS.NAME VALUE`, `write`.
    fn run_script(&mut self) {
        let lines: Vec<String> = self.script.as_ref().map(|rx| rx.try_iter().collect()).unwrap_or_default();
        for line in lines {
            match super::script::parse_line(&line) {
                Ok(Some(ScriptCommand::Quit)) => self.quit = true,
                Ok(Some(ScriptCommand::Screenshot(path))) => match super::screenshot_target(&path) {
                    Ok(()) => self.screenshots_now.push(path),
                    Err(e) => crate::stdout::eprintln_escaped!("script: {e}"),
                },
                Ok(Some(ScriptCommand::Param { pass, name, value })) => {
                    self.apply_actions(vec![Action::Param(pass, name, value)])
                }
                Ok(Some(ScriptCommand::Write)) => self.apply_actions(vec![Action::WriteBack]),
                Ok(Some(ScriptCommand::SaveScene(path))) => self.apply_actions(vec![Action::SaveScene(path)]),
                Ok(Some(ScriptCommand::TfPoint(point))) => {
                    let Some(session) = self.session.as_ref() else { continue };
                    if let Err(message) = session.workbench().edited_tf().check_value(point.value) {
                        crate::stdout::eprintln_escaped!("script: tf-point {message}");
                        continue;
                    }
                    let tf = super::tf_editor::with_point(session.transfer_function(), point);
                    self.apply_actions(vec![Action::TransferFunction(TfAction::Edit(tf))]);
                }
                Ok(Some(ScriptCommand::Slices(open))) => self.apply_actions(vec![Action::SlicePanes(open)]),
                Ok(Some(ScriptCommand::SliceWindow(window))) => self.apply_actions(vec![Action::SliceWindow(window)]),
                Ok(Some(ScriptCommand::Click(x, y))) => {
                    // A left click there, as the window's events would give it.
                    self.cursor = Some((x, y));
                    self.mouse_button(MouseButton::Left, true);
                    self.mouse_button(MouseButton::Left, false);
                }
                Ok(Some(ScriptCommand::Wheel(x, y, lines))) => {
                    self.cursor = Some((x, y));
                    self.mouse_wheel(lines);
                }
                Ok(Some(ScriptCommand::TfSave)) => self.apply_actions(vec![Action::TransferFunction(TfAction::Save)]),
                Ok(Some(ScriptCommand::Light(light))) => {
                    // The script moves the key light; the others stay.
                    let lights = self.session.as_ref().map_or(light.into(), |s| s.runtime.lights().with_key(light));
                    self.apply_actions(vec![Action::Lights(lights)])
                }
                Ok(Some(ScriptCommand::Label(edit))) => self.apply_actions(vec![Action::Labels(edit)]),
                Ok(Some(ScriptCommand::TfEdit(input))) => {
                    let Some(session) = self.session.as_mut() else { continue };
                    if let Err(message) = session.select_transfer_function(&input) {
                        crate::stdout::eprintln_escaped!("script: tf-edit {message}");
                    }
                }
                Ok(Some(ScriptCommand::Crop(crop))) => {
                    let Some(session) = self.session.as_ref() else { continue };
                    let planes: Vec<_> = session.runtime.cuts().planes().copied().collect();
                    match volgraph_accel::cuts::Cuts::new(crop, &planes) {
                        Ok(cuts) => self.apply_actions(vec![Action::Cuts(cuts)]),
                        Err(e) => crate::stdout::eprintln_escaped!("script: crop: {e}"),
                    }
                }
                Ok(Some(ScriptCommand::Clip(plane))) => {
                    let Some(session) = self.session.as_ref() else { continue };
                    let crop = session.runtime.cuts().crop();
                    match volgraph_accel::cuts::Cuts::new(crop, plane.as_slice()) {
                        Ok(cuts) => self.apply_actions(vec![Action::Cuts(cuts)]),
                        Err(e) => crate::stdout::eprintln_escaped!("script: clip: {e}"),
                    }
                }
                Ok(None) => {}
                Err(message) => crate::stdout::eprintln_escaped!("script: {message}"),
            }
        }
    }

    /// A mouse button at the pointer: on a slice pane the left button moves the crosshair (and
    /// drags it); elsewhere left and middle turn and pan the camera.
    fn mouse_button(&mut self, button: MouseButton, pressed: bool) {
        let on_pane = self.pane_under_cursor();
        let slice_click = pressed && on_pane.is_some() || !pressed && self.slice_drag.is_some();
        if button == MouseButton::Left && slice_click {
            self.slice_drag = on_pane.filter(|_| pressed).map(|(axis, _)| axis);
            if pressed {
                self.move_crosshair();
            }
        } else if matches!(button, MouseButton::Left | MouseButton::Middle) {
            let pan = button == MouseButton::Middle || self.modifiers.shift_key();
            self.orbit.button(pressed, pan);
        }
    }

    /// The wheel at the pointer: over a slice pane it steps through its slices (a notch a slice,
    /// up toward the higher index); elsewhere it zooms.
    fn mouse_wheel(&mut self, lines: f64) {
        if let Some((axis, _)) = self.pane_under_cursor() {
            if let Some(panes) = self.session.as_mut().and_then(LiveSession::slices_mut) {
                panes.scroll(axis, lines.signum() as i32 * lines.abs().ceil().max(1.0) as i32);
            }
        } else {
            self.orbit.wheel(lines);
            self.frames.moved();
        }
    }

    /// The four-up layout while the slice panes are open.
    fn four_up(&self) -> Option<FourUp> {
        let gfx = self.gfx.as_ref()?;
        self.session.as_ref()?.slices()?;
        Some(FourUp::of(image_size((gfx.config.width, gfx.config.height), self.panel_px)))
    }

    /// The slice pane under the pointer and the pointer's point in it (pixels).
    fn pane_under_cursor(&self) -> Option<(volgraph_accel::reslice::SliceAxis, glam::DVec2)> {
        let (x, y) = self.cursor?;
        self.four_up()?.pane_at(glam::DVec2::new(x, y))
    }

    /// Moves the crosshair to the pointer in the pane being dragged in (clamped to its slice).
    fn move_crosshair(&mut self) {
        let (Some(axis), Some(layout), Some((x, y))) = (self.slice_drag, self.four_up(), self.cursor) else { return };
        let index = volgraph_accel::reslice::SliceAxis::ALL.iter().position(|a| *a == axis).unwrap_or(0);
        let [px, py, _, _] = layout.panes[index];
        let local = glam::DVec2::new(x - f64::from(px), y - f64::from(py));
        if let Some(panes) = self.session.as_mut().and_then(LiveSession::slices_mut) {
            panes.click(axis, layout.pane(), local);
        }
    }

    fn save_screenshot(&mut self, path: &PathBuf) -> Result<(), String> {
        // A FIFO here would block the window for good: refused now with the screenshot's own
        // message, and the PNG is written with `write_bytes_atomically`, which never opens the
        // path itself (a FIFO made after this check is refused or replaced, never waited on).
        super::screenshot_target(path)?;
        let (Some(session), Some(gfx)) = (self.session.as_mut(), self.gfx.as_ref()) else { return Ok(()) };
        let output = session.shown_output();
        // The image as the window shows it beside the panel (not stretched over the window).
        let slices = session.slices().is_some();
        let (w, h) = view_size((gfx.config.width, gfx.config.height), self.panel_px, slices);
        let bytes = session.runtime.capture(output, gfx.config.format, (w, h)).map_err(|e| e.to_string())?;
        let bgra = matches!(gfx.config.format, wgpu::TextureFormat::Bgra8Unorm | wgpu::TextureFormat::Bgra8UnormSrgb);
        let mut rgba = bytes;
        if bgra {
            for px in rgba.chunks_exact_mut(4) {
                px.swap(0, 2);
            }
        }
        for px in rgba.chunks_exact_mut(4) {
            px[3] = 255;
        }
        let image = image::RgbaImage::from_raw(w, h, rgba).ok_or("screenshot size mismatch")?;
        let mut png = Vec::new();
        image
            .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
            .map_err(|e| format!("{}: cannot encode the screenshot: {e}", path.display()))?;
        crate::atomic_write::write_bytes_atomically(path, &png)
            .map_err(|e| format!("cannot write the screenshot: {e:#}"))?;
        crate::stdout::println_escaped!("screenshot {}", path.display());
        Ok(())
    }

    fn redraw(&mut self, event_loop: &ActiveEventLoop) {
        // Level of detail: fewer pixels while the camera moves, the full image once it rests.
        let mut lod_events = Vec::new();
        if let (Some(session), Some(gfx)) = (self.session.as_mut(), self.gfx.as_ref()) {
            let image = view_size((gfx.config.width, gfx.config.height), self.panel_px, session.slices().is_some());
            lod_events = self.frames.apply_lod(image, session);
        }
        self.handle(lod_events);
        let Some(session) = self.session.as_mut() else { return };
        for stats in session.runtime.poll() {
            self.timings.add(&stats);
            self.frames.observe(stats.frame_index, stats.frame_ms);
        }
        let Some(gfx) = self.gfx.as_mut() else { return };
        let frame = match gfx.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(f) | wgpu::CurrentSurfaceTexture::Suboptimal(f) => f,
            wgpu::CurrentSurfaceTexture::Outdated | wgpu::CurrentSurfaceTexture::Lost => {
                gfx.surface.configure(&gfx.gpu.device, &gfx.config);
                return;
            }
            _ => return,
        };
        let view = frame.texture.create_view(&wgpu::TextureViewDescriptor::default());
        let size = (gfx.config.width, gfx.config.height);
        let four_up = session.slices().is_some().then(|| FourUp::of(image_size(size, self.panel_px)));
        let image = view_size(size, self.panel_px, four_up.is_some());
        let target = PresentTarget {
            view: &view,
            format: gfx.config.format,
            size,
            output: session.shown_output(),
            region: Some([0, 0, image.0, image.1]),
            load: false,
        };
        if let Some(turn) = self.view.turn_degrees {
            self.orbit.turn(turn);
            self.frames.changed();
        }
        let events = match session.frame(&self.orbit.camera, Some(&target)) {
            Ok(events) => events,
            Err(e) => {
                drop(frame);
                self.fail(event_loop, format!("a frame failed and no earlier graph renders: {e}"));
                return;
            }
        };
        let reverted = !events.is_empty();
        self.handle(events);
        if reverted {
            // This frame's surface texture was not drawn: show the next one.
            return;
        }
        let Some(session) = self.session.as_mut() else { return };
        let Some(gfx) = self.gfx.as_mut() else { return };
        // The slice panes beside the 3D view: rendered again only when the crosshair, the window
        // or the pane size changed, drawn every frame.
        if let (Some(layout), Some(panes)) = (four_up, session.slices_mut()) {
            let drawn =
                panes.update(layout.pane()).and_then(|_| panes.present(&view, gfx.config.format, size, &layout.panes));
            if let Err(message) = drawn {
                let events = session.set_slice_panes(false);
                let error = Event::Error { what: "slice panes".to_string(), message };
                self.handle(events.into_iter().chain([error]).collect());
                return;
            }
        }
        let Some(session) = self.session.as_mut() else { return };
        let Some(gfx) = self.gfx.as_mut() else { return };
        let mut actions = Vec::new();
        if self.panel_open {
            let raw = gfx.egui.take_egui_input(&gfx.window);
            let ctx = gfx.egui.egui_ctx().clone();
            let adapter = gfx.gpu.adapter_name.clone();
            // One ray on the CPU, only while the pointer is still (a drag turns the camera).
            let probe = self
                .cursor
                .filter(|_| !self.orbit.is_dragging())
                .and_then(|c| session.probe_line(&self.orbit.camera, c));
            // What accuracy costs, live: once the view has rested (and the full image is back),
            // one comparison with the converged reference on a worker thread.
            self.accuracy.poll();
            if self.frames.measure_now(self.orbit.is_dragging(), self.accuracy.busy()) {
                match session.accuracy_job(&self.orbit.camera) {
                    Some(job) => self.accuracy.start(job),
                    None => self.accuracy.last = None,
                }
            }
            let accuracy_line = self.frames.accuracy_line(self.accuracy.last.as_ref(), self.accuracy.busy());
            let mut panel_points = 0.0;
            // The orientation marker, for a volume in the patient frame, in the image's corner.
            let marker = session.in_patient_frame().then(|| {
                let (w, h) = view_size(size, self.panel_px, four_up.is_some());
                let ppp = ctx.pixels_per_point();
                (
                    egui::Rect::from_min_size(egui::Pos2::ZERO, egui::vec2(w as f32 / ppp, h as f32 / ppp)),
                    self.orbit.camera,
                )
            });
            let output = ctx.run_ui(raw, |ui| {
                if let Some((image, camera)) = &marker {
                    super::orientation::draw(ui.ctx(), *image, camera);
                }
                if let (Some(layout), Some(panes)) = (&four_up, session.slices()) {
                    let patient = session.in_patient_frame();
                    let ppp = ui.ctx().pixels_per_point();
                    super::slice_section::draw_overlay(ui.ctx(), layout, ppp, panes, &self.orbit.camera, patient);
                }
                let shown = panel::show(
                    ui,
                    session,
                    &self.timings,
                    &adapter,
                    probe.as_deref(),
                    self.frames.lod(),
                    &accuracy_line,
                );
                (actions, panel_points) = (shown.actions, shown.width);
            });
            let egui::FullOutput { platform_output, mut textures_delta, shapes, pixels_per_point, .. } = output;
            // The next frame's image fits beside the panel as drawn now.
            self.panel_px = (panel_points * pixels_per_point).ceil().max(0.0) as u32;
            gfx.egui.handle_platform_output(&gfx.window, platform_output);
            let jobs = ctx.tessellate(shapes, pixels_per_point);
            for (id, deltas) in textures_delta.set.drain() {
                for delta in &deltas {
                    gfx.renderer.update_texture(&gfx.gpu.device, &gfx.gpu.queue, id, delta);
                }
            }
            let screen = egui_wgpu::ScreenDescriptor { size_in_pixels: [size.0, size.1], pixels_per_point };
            let mut encoder =
                gfx.gpu.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("overlay") });
            let uploads = gfx.renderer.update_buffers(&gfx.gpu.device, &gfx.gpu.queue, &mut encoder, &jobs, &screen);
            {
                let mut pass = encoder
                    .begin_render_pass(&wgpu::RenderPassDescriptor {
                        label: Some("overlay"),
                        color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                            view: &view,
                            depth_slice: None,
                            resolve_target: None,
                            ops: wgpu::Operations { load: wgpu::LoadOp::Load, store: wgpu::StoreOp::Store },
                        })],
                        ..Default::default()
                    })
                    .forget_lifetime();
                gfx.renderer.render(&mut pass, &jobs, &screen);
            }
            gfx.gpu.queue.submit(uploads.into_iter().chain([encoder.finish()]));
            for id in textures_delta.free.drain() {
                gfx.renderer.free_texture(&id);
            }
        }
        gfx.gpu.queue.present(frame);
        self.timings.frames += 1;
        self.apply_actions(actions);
        for path in std::mem::take(&mut self.screenshots_now) {
            if let Err(e) = self.save_screenshot(&path) {
                crate::stdout::eprintln_escaped!("error: {e}");
            }
        }
        let done = self.view.frames.is_some_and(|n| self.timings.frames >= n);
        if done || self.quit {
            if let Some(path) = self.view.screenshot.clone()
                && let Err(e) = self.save_screenshot(&path)
            {
                self.fail(event_loop, e);
                return;
            }
            crate::stdout::println_escaped!("presented {} frames", self.timings.frames);
            event_loop.exit();
        }
    }
}

impl ApplicationHandler for Viewer {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.gfx.is_none()
            && let Err(e) = self.start(event_loop)
        {
            self.fail(event_loop, e);
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _id: WindowId, event: WindowEvent) {
        let consumed = match self.gfx.as_mut() {
            Some(gfx) if self.panel_open => gfx.egui.on_window_event(&gfx.window, &event).consumed,
            _ => false,
        };
        match event {
            WindowEvent::CloseRequested => event_loop.exit(),
            WindowEvent::Resized(size) => {
                if let Some(gfx) = self.gfx.as_mut()
                    && size.width > 0
                    && size.height > 0
                {
                    gfx.config.width = size.width;
                    gfx.config.height = size.height;
                    gfx.surface.configure(&gfx.gpu.device, &gfx.config);
                }
                if let Some(session) = self.session.as_mut() {
                    let slices = session.slices().is_some();
                    let (w, h) = view_size((size.width, size.height), self.panel_px, slices);
                    let events = session.resize(w, h);
                    self.handle(events);
                }
            }
            WindowEvent::RedrawRequested => self.redraw(event_loop),
            WindowEvent::ModifiersChanged(m) => self.modifiers = m.state(),
            WindowEvent::KeyboardInput { event, .. } if !consumed && event.state == ElementState::Pressed => {
                match event.logical_key {
                    Key::Named(NamedKey::Escape) => event_loop.exit(),
                    Key::Named(NamedKey::F1) => {
                        self.panel_open = !self.panel_open;
                        // Closed, the image takes the whole window; open, the panel's width as
                        // last drawn (the next frame fits it).
                        if !self.panel_open {
                            self.panel_px = 0;
                        }
                    }
                    Key::Character(c) if c.eq_ignore_ascii_case("r") => self.orbit.reset(),
                    // 1–6: the patient views (anterior, posterior, left, right, superior,
                    // inferior), superior up, at the current distance.
                    Key::Character(c) if matches!(c.as_str(), "1" | "2" | "3" | "4" | "5" | "6") => {
                        let index = c.as_str().parse::<usize>().unwrap_or(1) - 1;
                        let (_, view) = volgraph_accel::camera::PatientView::ALL[index];
                        self.apply_actions(vec![Action::PatientView(view)]);
                    }
                    Key::Character(c) if c.eq_ignore_ascii_case("m") => {
                        let open = self.session.as_ref().is_some_and(|s| s.slices().is_some());
                        self.apply_actions(vec![Action::SlicePanes(!open)]);
                    }
                    Key::Character(c) if c.eq_ignore_ascii_case("s") => {
                        self.apply_actions(vec![Action::Screenshot]);
                    }
                    _ => {}
                }
            }
            WindowEvent::MouseInput { state, button, .. } if !consumed => {
                self.mouse_button(button, state == ElementState::Pressed);
            }
            WindowEvent::CursorMoved { position, .. } => {
                self.cursor = Some((position.x, position.y));
                if self.slice_drag.is_some() {
                    self.move_crosshair();
                    return;
                }
                if self.orbit.is_dragging() {
                    self.frames.moved();
                }
                let height = self.gfx.as_ref().map_or(1.0, |g| g.config.height as f64);
                self.orbit.moved(position.x, position.y, height);
            }
            WindowEvent::MouseWheel { delta, .. } if !consumed => {
                let lines = match delta {
                    MouseScrollDelta::LineDelta(_, y) => y as f64,
                    MouseScrollDelta::PixelDelta(p) => p.y / 40.0,
                };
                self.mouse_wheel(lines);
            }
            _ => {}
        }
    }

    fn about_to_wait(&mut self, _event_loop: &ActiveEventLoop) {
        self.run_script();
        let changed = self.watch.as_mut().map(FileWatch::poll).unwrap_or_default();
        if !changed.is_empty()
            && let Some(session) = self.session.as_mut()
        {
            let events = session.files_changed(&changed);
            self.handle(events);
        }
        if let Some(gfx) = &self.gfx {
            gfx.window.request_redraw();
        }
    }
}

/// Runs the viewer until the window closes, `--frames` are presented or the script says quit.
pub fn run(session_args: SessionArgs, view: ViewOptions, script: Option<Receiver<String>>) -> Result<(), String> {
    let event_loop = EventLoop::new().map_err(|e| {
        format!("cannot open a window ({e}); volgraph view needs a display (X11: set DISPLAY, or run under Xvfb)")
    })?;
    event_loop.set_control_flow(ControlFlow::Poll);
    let mut viewer = Viewer::new(session_args, view, script);
    event_loop.run_app(&mut viewer).map_err(|e| format!("the window's event loop failed: {e}"))?;
    match viewer.failure {
        Some(e) => Err(e),
        None => Ok(()),
    }
}

/// The 3D view's size: the image beside the panel, or its top-left quarter with the slice panes
/// open (`FourUp`).
fn view_size(surface: (u32, u32), panel_px: u32, slices: bool) -> (u32, u32) {
    let image = image_size(surface, panel_px);
    if slices { FourUp::of(image).pane() } else { image }
}

/// The image's size in a window of `surface` pixels with a panel `panel_px` wide at its right:
/// the rest of the window (at least a quarter of its width and a pixel).
fn image_size(surface: (u32, u32), panel_px: u32) -> (u32, u32) {
    let (w, h) = surface;
    (w.saturating_sub(panel_px).max(w / 4).max(1), h.max(1))
}
