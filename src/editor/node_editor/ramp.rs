//! The colour-ramp widget, as Blender's Color Ramp: a gradient bar over a strip of stop
//! markers, and the selected stop's colour and position below.
//!
//! Click the bar to add a stop there (with the colour the ramp has at that point), drag a
//! marker to move its stop (kept within [0, 1], the stops kept sorted), click a marker to
//! select its stop, edit the selected stop's colour (linear RGBA) and position, delete it
//! (never the last one). Each change returns the whole new stop list, to be set as the
//! node's parameter; a drag or a picker's change returns the gesture it merges under, so
//! that one drag is one undo step.

use egui::{Color32, Pos2, Rect, Sense, Stroke, Ui, vec2};

use crate::editor::document::GestureId;
use crate::material::RampStop;

/// How a ramp blends between stops: its node's `interpolation` parameter.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Interpolation {
    Linear,
    /// The stop on the left holds until the next (Blender's "Constant").
    Constant,
    /// Smoothstep between stops.
    Ease,
}

impl Interpolation {
    /// The mode the node's `interpolation` choice names (linear for anything else, as
    /// the compiler's default).
    pub fn from_choice(choice: &str) -> Self {
        match choice {
            "constant" => Self::Constant,
            "ease" => Self::Ease,
            _ => Self::Linear,
        }
    }
}

/// The ramp's colour at `t`, as the compiled ramp computes it (`nd_ramp_mix`): the
/// first stop's colour up to it, the last's after it, blended by `mode` between. `stops`
/// must be sorted by position.
pub fn ramp_at(stops: &[RampStop], t: f32, mode: Interpolation) -> [f32; 4] {
    let Some(first) = stops.first() else {
        return [0.0, 0.0, 0.0, 1.0];
    };
    if t <= first.position {
        return first.color;
    }
    for w in stops.windows(2) {
        let (a, b) = (&w[0], &w[1]);
        if t <= b.position {
            if mode == Interpolation::Constant {
                return a.color;
            }
            let mut f = ((t - a.position) / (b.position - a.position).max(1e-8)).clamp(0.0, 1.0);
            if mode == Interpolation::Ease {
                f = f * f * (3.0 - 2.0 * f);
            }
            return std::array::from_fn(|i| a.color[i] + (b.color[i] - a.color[i]) * f);
        }
    }
    stops[stops.len() - 1].color
}

/// `stops` sorted by position (stable: stops at the same position keep their order).
pub fn sorted(stops: &[RampStop]) -> Vec<RampStop> {
    let mut stops = stops.to_vec();
    stops.sort_by(|a, b| a.position.total_cmp(&b.position));
    stops
}

/// The stops with a new stop at `t` (clamped to [0, 1]) of the colour the ramp has there;
/// returns them sorted, and the new stop's index.
pub fn add_stop(stops: &[RampStop], t: f32, mode: Interpolation) -> (Vec<RampStop>, usize) {
    let mut stops = sorted(stops);
    let t = t.clamp(0.0, 1.0);
    let color = ramp_at(&stops, t, mode);
    // After the stops at the same position, so that it lands where the bar was clicked.
    let index = stops.partition_point(|s| s.position <= t);
    stops.insert(index, RampStop { position: t, color });
    (stops, index)
}

/// The stops with stop `index` moved to `t` (clamped to [0, 1]); returns them sorted and
/// where the moved stop now is.
pub fn move_stop(stops: &[RampStop], index: usize, t: f32) -> (Vec<RampStop>, usize) {
    let mut stops = sorted(stops);
    if index >= stops.len() {
        return (stops, index);
    }
    let mut moved = stops.remove(index);
    moved.position = t.clamp(0.0, 1.0);
    let index = stops.partition_point(|s| s.position <= moved.position);
    stops.insert(index, moved);
    (stops, index)
}

/// The stops without stop `index`; None when it is the last one (a ramp keeps one stop).
pub fn delete_stop(stops: &[RampStop], index: usize) -> Option<Vec<RampStop>> {
    let mut stops = sorted(stops);
    if stops.len() <= 1 || index >= stops.len() {
        return None;
    }
    stops.remove(index);
    Some(stops)
}

/// The gradient bar's size in points.
const BAR: egui::Vec2 = vec2(180.0, 18.0);
/// The height of the strip under the bar that holds the stop markers.
const MARKERS: f32 = 12.0;
/// How far from a marker (in points across) a press still takes it.
const GRAB: f32 = 6.0;

/// What the widget keeps between frames: the selected stop, and the stop being dragged.
#[derive(Clone, Copy, Debug, Default)]
struct State {
    selected: usize,
    dragging: Option<usize>,
}

/// Draws the ramp editor for `stops` (the node's, as stored: sorted here) under the egui
/// id `id`, blending as `mode` does. Returns the new stops when the user changed them,
/// with the gesture the change belongs to (None: a step of its own).
pub fn ramp_ui(
    ui: &mut Ui,
    id: egui::Id,
    stops: &[RampStop],
    mode: Interpolation,
) -> Option<(Vec<RampStop>, Option<GestureId>)> {
    let stops = if stops.is_empty() {
        crate::material::nodes::default_ramp_stops()
    } else {
        sorted(stops)
    };
    let mut state: State = ui.data(|d| d.get_temp(id)).unwrap_or_default();
    state.selected = state.selected.min(stops.len() - 1);
    let mut changed = None;

    // The bar: a click adds a stop where it lands.
    let (bar, bar_response) = ui.allocate_exact_size(BAR, Sense::click());
    let bar_response = bar_response.on_hover_text("Click to add a stop here");
    bar_response
        .widget_info(|| egui::WidgetInfo::labeled(egui::WidgetType::Other, true, "color ramp"));
    paint_gradient(ui, bar, &stops, mode);
    let t_at = |x: f32| (x - bar.left()) / bar.width();
    if bar_response.clicked() {
        if let Some(p) = bar_response.interact_pointer_pos() {
            let (new, index) = add_stop(&stops, t_at(p.x), mode);
            state.selected = index;
            changed = Some((new, None));
        }
    }

    // The markers: press one to select it, drag it to move its stop.
    let (strip, strip_response) =
        ui.allocate_exact_size(vec2(BAR.x, MARKERS), Sense::click_and_drag());
    strip_response.widget_info(|| {
        egui::WidgetInfo::labeled(egui::WidgetType::Other, true, "color ramp stops")
    });
    let marker_x = |s: &RampStop| bar.left() + s.position.clamp(0.0, 1.0) * bar.width();
    let nearest = |p: Pos2| {
        stops
            .iter()
            .enumerate()
            .map(|(i, s)| (i, (marker_x(s) - p.x).abs()))
            .filter(|(_, d)| *d <= GRAB)
            // The last of equally near ones: the one drawn on top.
            .min_by(|a, b| a.1.total_cmp(&b.1).then(b.0.cmp(&a.0)))
            .map(|(i, _)| i)
    };
    if strip_response.drag_started() || strip_response.clicked() {
        // Where the button went down (a drag starts some points away from it), in the
        // coordinates of the layer the ramp is drawn on (the canvas's, scaled and moved).
        let from_global = ui
            .ctx()
            .layer_transform_from_global(ui.layer_id())
            .unwrap_or_default();
        let pressed = ui
            .input(|i| i.pointer.press_origin())
            .map(|p| from_global * p)
            .or(strip_response.interact_pointer_pos());
        if let Some(i) = pressed.and_then(nearest) {
            state.selected = i;
            state.dragging = strip_response.drag_started().then_some(i);
        }
    }
    if let (Some(i), true) = (state.dragging, strip_response.dragged()) {
        if let Some(p) = strip_response.interact_pointer_pos() {
            let (new, index) = move_stop(&stops, i, t_at(p.x));
            if new != stops {
                changed = Some((new, Some(strip_response.id.value())));
            }
            state.dragging = Some(index);
            state.selected = index;
        }
    }
    if strip_response.drag_stopped() {
        state.dragging = None;
    }
    paint_markers(ui, strip, &stops, state.selected, marker_x);

    // The selected stop: its colour, its position, and a button to delete it.
    let selected = state.selected;
    let stop = &stops[selected];
    ui.horizontal(|ui| {
        let mut color = stop.color;
        // One label for the stop's two fields, to keep the row as narrow as the bar.
        let label = ui.label("stop");
        let r = ui
            .color_edit_button_rgba_unmultiplied(&mut color)
            .labelled_by(label.id)
            .on_hover_text(
                "The stop's colour: linear RGB (scene-referred) and alpha; the picker shows \
                 it as sRGB",
            );
        if r.changed() {
            let mut new = stops.clone();
            new[selected].color = color;
            changed = Some((new, Some(r.id.value())));
        }
        let mut position = stop.position;
        let r = ui
            .add(
                egui::DragValue::new(&mut position)
                    .range(0.0..=1.0)
                    .speed(0.005)
                    .max_decimals(3),
            )
            .labelled_by(label.id)
            .on_hover_text("The stop's position along the ramp, 0 to 1");
        if r.changed() && position != stop.position {
            let (new, index) = move_stop(&stops, selected, position);
            state.selected = index;
            changed = Some((new, r.dragged().then(|| r.id.value())));
        }
        let r = ui
            .add_enabled(stops.len() > 1, egui::Button::new("Delete stop"))
            .on_hover_text("Remove the selected stop (a ramp keeps at least one)")
            .on_disabled_hover_text("A ramp keeps at least one stop");
        if r.clicked() {
            if let Some(new) = delete_stop(&stops, selected) {
                state.selected = selected.saturating_sub(1);
                changed = Some((new, None));
            }
        }
    });
    ui.data_mut(|d| d.insert_temp(id, state));
    changed
}

/// Paints the ramp as a gradient over a checkerboard (so that alpha shows).
fn paint_gradient(ui: &Ui, rect: Rect, stops: &[RampStop], mode: Interpolation) {
    let painter = ui.painter_at(rect);
    let cell = rect.height() / 2.0;
    let mut x = rect.left();
    let mut column = 0;
    while x < rect.right() {
        for row in 0..2 {
            let shade = if (column + row) % 2 == 0 { 0x99 } else { 0x66 };
            let cell_rect = Rect::from_min_size(
                Pos2::new(x, rect.top() + row as f32 * cell),
                vec2(cell, cell),
            )
            .intersect(rect);
            painter.rect_filled(cell_rect, 0.0, Color32::from_gray(shade));
        }
        x += cell;
        column += 1;
    }
    let steps = 64;
    for i in 0..steps {
        let t = (i as f32 + 0.5) / steps as f32;
        let c = ramp_at(stops, t, mode);
        let x0 = rect.left() + rect.width() * i as f32 / steps as f32;
        let x1 = rect.left() + rect.width() * (i + 1) as f32 / steps as f32;
        painter.rect_filled(
            Rect::from_x_y_ranges(x0..=x1, rect.y_range()),
            0.0,
            egui::Rgba::from_rgba_unmultiplied(c[0], c[1], c[2], c[3].clamp(0.0, 1.0)),
        );
    }
    painter.rect_stroke(
        rect,
        0.0,
        ui.visuals().widgets.noninteractive.bg_stroke,
        egui::StrokeKind::Inside,
    );
}

/// Paints a marker per stop: a small house shape pointing up at its place on the bar,
/// filled with its colour, the selected one outlined in white.
fn paint_markers(
    ui: &Ui,
    strip: Rect,
    stops: &[RampStop],
    selected: usize,
    marker_x: impl Fn(&RampStop) -> f32,
) {
    let painter = ui.painter_at(strip.expand2(vec2(GRAB, 0.0)));
    // The selected one last, on top.
    let order = (0..stops.len())
        .filter(|&i| i != selected)
        .chain(std::iter::once(selected));
    for i in order {
        let s = &stops[i];
        let x = marker_x(s);
        let (top, mid, bottom) = (strip.top(), strip.top() + 4.0, strip.bottom() - 1.0);
        let points = vec![
            Pos2::new(x, top),
            Pos2::new(x + 4.5, mid),
            Pos2::new(x + 4.5, bottom),
            Pos2::new(x - 4.5, bottom),
            Pos2::new(x - 4.5, mid),
        ];
        let stroke = if i == selected {
            Stroke::new(1.5, Color32::WHITE)
        } else {
            Stroke::new(1.0, Color32::BLACK)
        };
        painter.add(egui::Shape::convex_polygon(
            points,
            Color32::from(egui::Rgba::from_rgb(s.color[0], s.color[1], s.color[2])),
            stroke,
        ));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn stop(position: f32, grey: f32) -> RampStop {
        RampStop {
            position,
            color: [grey, grey, grey, 1.0],
        }
    }

    #[test]
    fn an_added_stop_takes_the_ramps_colour_there_and_keeps_the_order() {
        let stops = vec![stop(1.0, 1.0), stop(0.0, 0.0)];
        let (new, index) = add_stop(&stops, 0.25, Interpolation::Linear);
        assert_eq!(index, 1);
        assert_eq!(new, vec![stop(0.0, 0.0), stop(0.25, 0.25), stop(1.0, 1.0)]);
        let (new, _) = add_stop(&stops, 0.25, Interpolation::Constant);
        assert_eq!(new[1], stop(0.25, 0.0));
        let (new, index) = add_stop(&stops, 7.0, Interpolation::Linear);
        assert_eq!((index, new[2].position), (2, 1.0), "clamped to the bar");
    }

    #[test]
    fn a_moved_stop_is_clamped_and_resorted() {
        let stops = vec![stop(0.0, 0.0), stop(0.5, 0.5), stop(1.0, 1.0)];
        let (new, index) = move_stop(&stops, 0, 0.75);
        assert_eq!(index, 1);
        assert_eq!(
            new.iter().map(|s| s.position).collect::<Vec<_>>(),
            [0.5, 0.75, 1.0]
        );
        let (new, index) = move_stop(&stops, 1, -3.0);
        assert_eq!((index, new[0].position, new[0].color[0]), (1, 0.0, 0.0));
        assert_eq!(new[1], stop(0.0, 0.5));
    }

    #[test]
    fn the_last_stop_cannot_be_deleted() {
        let stops = vec![stop(0.0, 0.0), stop(1.0, 1.0)];
        let one = delete_stop(&stops, 0).unwrap();
        assert_eq!(one, vec![stop(1.0, 1.0)]);
        assert_eq!(delete_stop(&one, 0), None);
        assert_eq!(delete_stop(&stops, 5), None);
    }

    #[test]
    fn the_ramp_blends_as_the_compiled_one() {
        let stops = vec![stop(0.2, 0.0), stop(0.6, 1.0)];
        assert_eq!(
            ramp_at(&stops, 0.0, Interpolation::Linear),
            stop(0.0, 0.0).color
        );
        assert_eq!(
            ramp_at(&stops, 0.9, Interpolation::Linear),
            stop(0.0, 1.0).color
        );
        assert!((ramp_at(&stops, 0.3, Interpolation::Linear)[0] - 0.25).abs() < 1e-6);
        assert!((ramp_at(&stops, 0.3, Interpolation::Ease)[0] - 0.15625).abs() < 1e-6);
        assert_eq!(ramp_at(&stops, 0.5, Interpolation::Constant)[0], 0.0);
    }
}
