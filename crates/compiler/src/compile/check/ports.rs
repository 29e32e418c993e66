//! Ports: the input, output and otherwise names a pass writes, and the types of its outputs.

use std::collections::BTreeMap;

use super::{Checker, PassInfo, ValueDesc};
use crate::decl::{Access, PortKind};
use crate::format::{TargetFormat, TargetSize};
use crate::graph::ast::PassDoc;
use crate::graph::locate::PassPath;
use crate::suggest::{closest, comma_list, guess_then};

impl Checker<'_> {
    pub(super) fn check_port_names(&mut self, p: &PassDoc, path: PassPath, info: &PassInfo) {
        let input_names: Vec<&str> = info.ports.iter().filter(|s| s.is_input()).map(|s| s.name).collect();
        let output_names: Vec<&str> = info.ports.iter().filter(|s| s.is_output()).map(|s| s.name).collect();
        // A misspelt input is one mistake: report the unknown name with its suggestion, not
        // also the port it was meant for as missing.
        let mut meant: Vec<&str> = Vec::new();
        for name in p.inputs.keys() {
            if !input_names.contains(&name.as_str()) {
                let mut help = format!("its inputs are: {}", comma_list(&input_names));
                if let Some(best) = closest(name, input_names.iter().copied()) {
                    help = format!("did you mean \"{best}\"? {help}");
                    meant.push(best);
                }
                self.err(
                    self.loc.pass_entry(path, &p.id, "inputs", name, true),
                    format!("pass \"{}\" ({}) has no input \"{name}\"", p.id, p.kind),
                    Some(help),
                );
            }
        }
        for port in info.ports.iter().filter(|s| s.is_input() && s.required) {
            if !p.inputs.contains_key(port.name) && !meant.contains(&port.name) {
                self.err(
                    self.loc.pass_field(path, &p.id, "inputs"),
                    format!("pass \"{}\" ({}) needs input \"{}\" ({})", p.id, p.kind, port.name, port.kind.describe()),
                    Some(format!("wire it: inputs: {{\"{}\": \"<pass>.<output>\"}}", port.name)),
                );
            }
        }
        for name in p.outputs.keys().chain(p.otherwise.keys()) {
            if !output_names.contains(&name.as_str()) {
                let mut help = format!("its outputs are: {}", comma_list(&output_names));
                help = guess_then(name, output_names.iter().copied(), "", help);
                let map = if p.outputs.contains_key(name) { "outputs" } else { "otherwise" };
                self.err(
                    self.loc.pass_entry(path, &p.id, map, name, true),
                    format!("pass \"{}\" ({}) has no output \"{name}\"", p.id, p.kind),
                    Some(help),
                );
            }
        }
    }

    pub(super) fn output_descs(&mut self, p: &PassDoc, path: PassPath, info: &PassInfo) -> BTreeMap<String, ValueDesc> {
        let mut out = BTreeMap::new();
        for port in info.ports.iter().filter(|s| s.access == Access::Write) {
            let decl = p.outputs.get(port.name).cloned().unwrap_or_default();
            let desc = match &port.kind {
                PortKind::Target { formats, .. } => {
                    let default = formats.first().copied().unwrap_or(TargetFormat::Rgba32Float);
                    let mut format = decl.format.unwrap_or(default);
                    // The scene's precision wins over the graph's float RGBA formats where the
                    // pass can write it.
                    if let Some(precision) = self.options.precision
                        && matches!(format, TargetFormat::Rgba16Float | TargetFormat::Rgba32Float)
                        && formats.contains(&precision.rgba())
                    {
                        format = precision.rgba();
                    }
                    if !formats.contains(&format) {
                        let names: Vec<&str> = formats.iter().map(|f| f.name()).collect();
                        self.err(
                            self.loc.pass_entry(path, &p.id, "outputs", port.name, false),
                            format!("output \"{}\" of pass \"{}\" cannot be {format}", port.name, p.id),
                            Some(format!("{} writes {}", p.kind, names.join(" or "))),
                        );
                    }
                    let size = decl.size.unwrap_or_default();
                    let bad_size = match size {
                        TargetSize::Viewport(s) => !(s.is_finite() && s > 0.0 && s <= 16.0),
                        TargetSize::Absolute(w, h) => w == 0 || h == 0 || w > 16384 || h > 16384,
                    };
                    if bad_size {
                        self.err(
                            self.loc.pass_entry(path, &p.id, "outputs", port.name, false),
                            format!("output \"{}\" of pass \"{}\" has size {size}", port.name, p.id),
                            Some(
                                "use Viewport(scale) with 0 < scale <= 16, or Absolute(w, h) with 1..=16384 pixels"
                                    .to_string(),
                            ),
                        );
                    }
                    ValueDesc::Target { format, size }
                }
                PortKind::Buffer { bytes, bytes_per_pixel } => {
                    ValueDesc::Buffer { bytes: *bytes, bytes_per_pixel: *bytes_per_pixel }
                }
                PortKind::Owned(t) => ValueDesc::Owned((*t).to_string()),
                PortKind::Volume | PortKind::VolumeVoxels => ValueDesc::Volume,
                PortKind::TransferFunction => ValueDesc::TransferFunction,
                PortKind::LabelTable => ValueDesc::LabelTable,
            };
            out.insert(port.name.to_string(), desc);
        }
        out
    }
}
