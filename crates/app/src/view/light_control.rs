//! The panel's "Light" section (issue "light that scatters", item 1): the headlight, or a
//! directional light placed by azimuth and elevation (`volgraph_accel::light::Light`, the orbit
//! camera's angles). A change is a frame uniform: no recompile, the next frame shows it.

use volgraph_accel::light::Light;

/// Where a directional light starts when the headlight is turned off: over the viewer's
/// shoulder-ish, up and to the left of the default camera.
const FIRST_DIRECTIONAL: Light = Light::Directional { azimuth_deg: -30.0, elevation_deg: 45.0 };

/// Draws the section for `light`; the new light when the user changed it.
pub fn light_section(ui: &mut egui::Ui, light: Light) -> Option<Light> {
    let mut next = light;
    ui.collapsing("Light", |ui| {
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
                    .map(|(name, v)| {
                        ui.add(egui::Slider::new(v, -4.0..=4.0).text(format!("point light {name}"))).changed()
                    })
                    .fold(false, |a, b| a | b);
                if moved {
                    next = Light::Point { x, y, z };
                }
            }
            Light::Headlight => {}
        }
    });
    (next != light).then_some(next)
}

#[cfg(test)]
mod tests {
    use egui_kittest::Harness;
    use egui_kittest::kittest::Queryable as _;

    use super::*;

    #[test]
    fn the_headlight_checkbox_and_sliders_set_the_light() {
        let mut h = Harness::builder().with_size(egui::Vec2::new(360.0, 240.0)).build_ui_state(
            |ui, light: &mut Light| {
                if let Some(next) = light_section(ui, *light) {
                    *light = next;
                }
            },
            Light::Headlight,
        );
        h.run();
        h.get_by_label("Light").click();
        h.run();
        h.get_by_label("headlight (from the eye)").click();
        h.run();
        assert_eq!(*h.state(), FIRST_DIRECTIONAL);
        h.get_by_role_and_label(egui::accesskit::Role::Slider, "elevation °").set_value_accesskit(10.0);
        h.run();
        assert!(matches!(*h.state(), Light::Directional { elevation_deg, .. } if (elevation_deg - 10.0).abs() < 1e-9));
        h.get_by_label("headlight (from the eye)").click();
        h.run();
        assert_eq!(*h.state(), Light::Headlight);
    }
}
