//! Plans coming and going on a [`Runtime`]: compiling graph text with the bound scene's values,
//! applying a plan (the live plan rebuilt with reuse, `super::live_plan`; on error the previous one
//! keeps running) and the shader hot-reload hooks that mark nodes for rebuilding.

use super::{ApplyReport, Runtime, RuntimeError, live_plan, shaders};
use crate::diagnostic::Diagnostics;
use crate::plan::Plan;
use crate::plugin::Registry;
use crate::{CompileOptions, compile, cut_effects};

impl Runtime {
    /// Compiles graph text with the scene values of what is bound (a pure function; nothing is
    /// applied).
    pub fn compile(
        &self,
        file: &str,
        source: &str,
        registry: &Registry,
        options: &CompileOptions,
    ) -> Result<Plan, Diagnostics> {
        let mut options = options.clone();
        for (k, v) in self.scene_values() {
            options.scene.entry(k).or_insert(v);
        }
        compile(file, source, registry, &options)
    }

    /// Makes `plan` the running plan, reusing what did not change; on error the previous plan
    /// keeps running.
    pub fn apply(&mut self, plan: Plan, registry: &Registry) -> Result<ApplyReport, RuntimeError> {
        // The graph's own WGSL-only kinds join the registry for this plan.
        let extended;
        let registry = if plan.kinds.is_empty() {
            registry
        } else {
            extended = crate::wgsl_pass::with_graph_kinds(registry, &plan.kinds);
            &extended
        };
        let viewport_changed = self.plan().is_some_and(|p| p.viewport != plan.viewport);
        let cut_defines = self.frame_defines_for(&plan.features);
        let old = self.live.take();
        let resources = live_plan::Resources {
            gpu: &self.gpu,
            shaders: &self.shaders,
            pipelines: &self.pipelines,
            textures: &mut self.textures,
            history: &mut self.history,
        };
        match live_plan::build(resources, registry, plan, old, &self.stale_modules, &cut_defines) {
            Ok((live, report)) => {
                // Klein et al. 2005 §4.1: a resize starts from scratch, and so does a parameter
                // edit of a pass a history entry declares it depends on (an isovalue change).
                let stale = live
                    .plan
                    .history
                    .values()
                    .any(|h| h.reset_on_params_of.iter().any(|p| report.changed_passes.contains(p)));
                // A measure taken at another size or with other parameters says nothing now.
                self.bypasses.for_plan(&self.gpu, &live.plan, !(viewport_changed || stale));
                self.live = Some(live);
                self.stale_modules.clear();
                if viewport_changed || stale {
                    self.invalidate_history();
                }
                Ok(report)
            }
            Err((e, old)) => {
                self.live = old;
                Err(e.into())
            }
        }
    }

    /// The compiled shader modules now in use ([`ShaderLibrary::snapshot`](super::ShaderLibrary::snapshot)): a viewer takes one
    /// when a graph has rendered, to fall back on.
    pub fn shader_snapshot(&self) -> shaders::ShaderSnapshot {
        self.shaders.snapshot()
    }

    /// Puts back the modules of `snapshot` and marks those that differ stale, so the next
    /// [`Self::apply`] rebuilds their nodes from the good modules instead of re-reading an edit
    /// the GPU rejected.
    pub fn restore_shaders(&mut self, snapshot: &shaders::ShaderSnapshot) {
        let changed = self.shaders.restore(snapshot);
        self.stale_modules.extend(changed);
    }

    /// Forgets the cached modules built from `changed` files; the next [`Self::apply`] rebuilds
    /// exactly the nodes whose pipelines use them. Returns the modules affected.
    pub fn shaders_changed(&mut self, changed: &[std::path::PathBuf]) -> Vec<String> {
        let stale = self.shaders.invalidate(changed);
        self.stale_modules.extend(stale.iter().cloned());
        stale
    }

    /// The frame `#if` names a plan with `features` is built with (for the passes that honour a
    /// sub-box of the volume): the plan's and the set cuts', and the window's while one is set.
    fn frame_defines_for(&self, features: &std::collections::BTreeSet<String>) -> Vec<&'static str> {
        let mut all = cut_effects::features_of(&self.cuts);
        all.extend(features.iter().cloned());
        cut_effects::frame_defines(&all, self.window.is_some())
    }
}
