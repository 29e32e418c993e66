//! The panel's "Light" section (issue "light that scatters", item 1): up to three lights
//! (`volgraph_accel::light::Lights`), each the headlight, a directional light placed by azimuth
//! and elevation (the orbit camera's angles) or a point light; lights are added and removed
//! here. A change is a frame uniform: no recompile, the next frame shows it.

use volgraph_accel::light::{Light, Lights, MAX_LIGHTS};

/// Where a directional light starts when the headlight is turned off: over the viewer's
/// shoulder-ish, up and to the left of the default camera.
const FIRST_DIRECTIONAL: Light = Light::Directional { azimuth_deg: -30.0, elevation_deg: 45.0 };

/// Where an added light starts: a fill light low on the other side.
const ADDED: Light = Light::Directional { azimuth_deg: 60.0, elevation_deg: 10.0 };

/// Draws the section for `lights`; the new lights when the user changed them.
pub fn lights_section(ui: &mut egui::Ui, lights: Lights) -> Option<Lights> {
    let mut list = lights.as_slice().to_vec();
    // Open from the start where the scene brings several lights: they are what it is about.
    egui::CollapsingHeader::new("Light").default_open(list.len() > 1).show(ui, |ui| {
        let count = list.len();
        let mut remove = None;
        for (i, light) in list.iter_mut().enumerate() {
            ui.push_id(i, |ui| {
                if count > 1 {
                    ui.horizontal(|ui| {
                        ui.label(if i == 0 { "light 1 (key)".to_string() } else { format!("light {}", i + 1) });
                        if i > 0 && ui.small_button(format!("remove light {}", i + 1)).clicked() {
                            remove = Some(i);
                        }
                    });
                }
                if let Some(next) = one_light(ui, *light) {
                    *light = next;
                }
            });
        }
        if let Some(i) = remove {
            list.remove(i);
        }
        if list.len() < MAX_LIGHTS && ui.button("add a light").clicked() {
            list.push(ADDED);
        }
    });
    // One to MAX_LIGHTS lights, each from a slider's range: always valid.
    let next = Lights::new(&list).ok()?;
    (next != lights).then_some(next)
}

/// The controls of one light; the new light when the user changed it.
fn one_light(ui: &mut egui::Ui, light: Light) -> Option<Light> {
    let mut next = light;
    let mut headlight = matches!(light, Light::Headlight);
    if ui.checkbox(&mut headlight, "headlight (from the eye)").changed() {
        next = if headlight { Light::Headlight } else { FIRST_DIRECTIONAL };
    }
    match next {
        Light::Directional { mut azimuth_deg, mut elevation_deg } => {
            let az = ui.add(egui::Slider::new(&mut azimuth_deg, -180.0..=180.0).text("azimuth °"));
            let el = ui.add(egui::Slider::new(&mut elevation_deg, -90.0..=90.0).text("elevation °"));
            if az.changed() || el.changed() {
                next = Light::Directional { azimuth_deg, elevation_deg };
            }
        }
        Light::Point { mut x, mut y, mut z } => {
            // World units: the volume's box is centred on the origin, its longest side 2.
            let moved = [("x", &mut x), ("y", &mut y), ("z", &mut z)]
                .into_iter()
                .map(|(name, v)| ui.add(egui::Slider::new(v, -4.0..=4.0).text(format!("point light {name}"))).changed())
                .fold(false, |a, b| a | b);
            if moved {
                next = Light::Point { x, y, z };
            }
        }
        Light::Headlight => {}
    }
    (next != light).then_some(next)
}

#[cfg(test)]
mod tests {
    use egui_kittest::Harness;
    use egui_kittest::kittest::Queryable as _;

    use super::*;

    fn harness(lights: Lights) -> Harness<'static, Lights> {
        Harness::builder().with_size(egui::Vec2::new(360.0, 420.0)).build_ui_state(
            |ui, lights: &mut Lights| {
                if let Some(next) = lights_section(ui, *lights) {
                    *lights = next;
                }
            },
            lights,
        )
    }

    #[test]
    fn the_headlight_checkbox_and_sliders_set_the_light() {
        let mut h = harness(Lights::default());
        h.run();
        h.get_by_label("Light").click();
        h.run();
        h.get_by_label("headlight (from the eye)").click();
        h.run();
        assert_eq!(h.state().as_slice(), &[FIRST_DIRECTIONAL]);
        h.get_by_role_and_label(egui::accesskit::Role::Slider, "elevation °").set_value_accesskit(10.0);
        h.run();
        assert!(
            matches!(h.state().key(), Light::Directional { elevation_deg, .. } if (elevation_deg - 10.0).abs() < 1e-9)
        );
        h.get_by_label("headlight (from the eye)").click();
        h.run();
        assert_eq!(h.state().as_slice(), &[Light::Headlight]);
    }

    /// Lights are added up to three (the button then goes), each moved by its own sliders, and
    /// removed — the key light stays.
    #[test]
    fn lights_are_added_moved_and_removed() {
        let mut h = harness(Lights::default());
        h.run();
        h.get_by_label("Light").click();
        h.run();
        h.get_by_label("add a light").click();
        h.run();
        assert_eq!(h.state().as_slice(), &[Light::Headlight, ADDED]);
        h.get_by_label("add a light").click();
        h.run();
        assert_eq!(h.state().as_slice().len(), 3);
        assert!(h.query_by_label("add a light").is_none(), "three is the most");
        // The second light's elevation slider (the key light, the headlight, has none).
        let sliders: Vec<_> = h.get_all_by_role(egui::accesskit::Role::Slider).collect();
        assert_eq!(sliders.len(), 4, "azimuth and elevation of lights 2 and 3");
        sliders[1].set_value_accesskit(-20.0);
        h.run();
        assert!(
            matches!(h.state().as_slice()[1], Light::Directional { elevation_deg, .. } if (elevation_deg + 20.0).abs() < 1e-9),
            "{:?}",
            h.state()
        );
        h.get_by_label("remove light 2").click();
        h.run();
        assert_eq!(h.state().as_slice(), &[Light::Headlight, ADDED], "light 3 moved up");
    }

    /// A scene with several lights opens the section by itself; with one it stays closed.
    #[test]
    fn several_lights_open_the_section() {
        let mut h = harness(Lights::new(&[Light::Headlight, ADDED]).expect("two"));
        h.run();
        assert!(h.query_by_label("remove light 2").is_some(), "open with two lights");
        let mut h = harness(Lights::default());
        h.run();
        assert!(h.query_by_label("add a light").is_none(), "closed with one");
    }
}
