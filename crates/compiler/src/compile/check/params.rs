//! Parameters: every value a pass's params (and the parameter overrides) give, checked
//! against the plugin's parameter specs.

use super::Checker;
use crate::decl::PassDecl;
use crate::graph::ast::PassDoc;
use crate::graph::locate::PassPath;
use crate::params::{ParamKind, ParamProblem, Params, check_param};
use crate::suggest::{comma_list, guess_then, quoted_list};

impl Checker<'_> {
    pub(super) fn check_params(&mut self, p: &PassDoc, path: PassPath, plugin: &dyn PassDecl) -> Params {
        let specs = plugin.params();
        let mut params = Params::defaults(&specs);
        let mut values: Vec<(String, ron::Value)> = p.params.iter().map(|(k, v)| (k.clone(), v.clone())).collect();
        let prefix = format!("{}.", p.id);
        for (key, value) in &self.options.param_overrides {
            if let Some(name) = key.strip_prefix(&prefix) {
                values.retain(|(k, _)| k != name);
                values.push((name.to_string(), value.clone()));
            }
        }
        for (name, written) in &values {
            // `"input.NAME"` stands for the value of a Scalar graph input (the scene's value
            // when the application sets one), shared by every pass that names it.
            let value = match written {
                ron::Value::String(text) if text.starts_with("input.") => {
                    let input = &text["input.".len()..];
                    match self.scalar_value(input) {
                        Some(v) => ron::Value::from(v),
                        None => {
                            self.err(
                                self.loc.pass_entry(path, &p.id, "params", name, false),
                                format!("parameter \"{name}\" of pass \"{}\" reads \"{text}\", which is not a Scalar graph input", p.id),
                                Some(format!("declare inputs: {{\"{input}\": Scalar(<default>)}}, or write the value itself")),
                            );
                            continue;
                        }
                    }
                }
                // `"feature.NAME"`: whether the scene turned effect NAME on (a bool the pass
                // specializes its shaders with).
                ron::Value::String(text) if text.starts_with("feature.") => {
                    let feature = &text["feature.".len()..];
                    if feature.is_empty() || !feature.chars().all(|c| c.is_ascii_alphanumeric() || c == '_') {
                        self.err(
                            self.loc.pass_entry(path, &p.id, "params", name, false),
                            format!(
                                "parameter \"{name}\" of pass \"{}\" reads \"{text}\", which names no feature",
                                p.id
                            ),
                            Some("write \"feature.shading\" (letters, digits and _ after \"feature.\")".to_string()),
                        );
                        continue;
                    }
                    self.features_read.insert(feature.to_string());
                    ron::Value::Bool(self.options.features.contains(feature))
                }
                other => other.clone(),
            };
            let value = &value;
            let Some(spec) = specs.iter().find(|s| s.name == name) else {
                let names: Vec<&str> = specs.iter().map(|s| s.name).collect();
                let mut help = format!("its parameters are: {}", comma_list(&names));
                help = guess_then(name, names.iter().copied(), "", help);
                self.err(
                    self.loc.pass_entry(path, &p.id, "params", name, true),
                    format!("pass \"{}\" ({}) has no parameter \"{name}\"", p.id, p.kind),
                    Some(help),
                );
                continue;
            };
            let range = match &spec.kind {
                ParamKind::Float { default, min, max } => format!("default {default}, range {min} to {max}"),
                ParamKind::UInt { default, min, max } => format!("default {default}, range {min} to {max}"),
                ParamKind::Bool { default } => format!("default {default}"),
                ParamKind::Choice { default, options } => {
                    format!("default \"{default}\", one of {}", quoted_list(options))
                }
            };
            let location = self.loc.pass_entry(path, &p.id, "params", name, false);
            match check_param(spec, value) {
                Ok(v) => params.set(name, v),
                Err(ParamProblem::WrongType { found }) => self.err(
                    location,
                    format!(
                        "parameter \"{name}\" of pass \"{}\" must be {}, found {found}",
                        p.id,
                        spec.kind.type_name()
                    ),
                    Some(format!("{} ({range})", spec.doc)),
                ),
                Err(ParamProblem::OutOfRange { value }) => self.err(
                    location,
                    format!("parameter \"{name}\" of pass \"{}\" is {value}, outside its range", p.id),
                    Some(format!("{} ({range})", spec.doc)),
                ),
                Err(ParamProblem::UnknownChoice { value }) => self.err(
                    location,
                    format!("parameter \"{name}\" of pass \"{}\" is \"{value}\", which is not a valid choice", p.id),
                    Some(format!("{} ({range})", spec.doc)),
                ),
            }
        }
        params
    }
}
