//! The poly-line graph editor of EcoMod's local parameters (`004_*.txt` §II.B): the auxiliary
//! parameter on the ordinate over the Gravelius (0–15) or Weibull (0–50) order on the abscissa;
//! control points are dragged (a point stays between its neighbours' abscissae, as the
//! species schema requires non-decreasing x, and within the parameter's bounds), added with a
//! double-click and removed with a right-click (two points always stay).

use eframe::egui;

/// What happened to a curve in one frame.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct CurveResponse {
    /// The points changed.
    pub changed: bool,
    /// The change starts a new gesture (a new undo step): a drag's first move, an added or
    /// removed point.
    pub started: bool,
    /// The control point under the pointer.
    pub hovered_point: Option<usize>,
    /// The pointer is over the graph.
    pub hovered: bool,
}

/// Size of the graph (points).
pub const GRAPH_SIZE: egui::Vec2 = egui::vec2(440.0, 120.0);

/// Accessibility label of point `i` of the curve `name` (how tests find it).
pub fn point_label(name: &str, i: usize) -> String {
    format!("{name} point {i}")
}

/// Moves point `i` of `pts` to `(x, y)` within `xr` × `yr` and between its neighbours' x.
pub fn move_point(pts: &mut [[f64; 2]], i: usize, x: f64, y: f64, xr: (f64, f64), yr: (f64, f64)) {
    let lo = if i > 0 { pts[i - 1][0] } else { xr.0 };
    let hi = if i + 1 < pts.len() { pts[i + 1][0] } else { xr.1 };
    pts[i] = [x.clamp(lo, hi.max(lo)), y.clamp(yr.0, yr.1)];
}

/// Inserts a point at `(x, y)` (clamped to the ranges) in abscissa order; returns its index.
pub fn add_point(pts: &mut Vec<[f64; 2]>, x: f64, y: f64, xr: (f64, f64), yr: (f64, f64)) -> usize {
    let p = [x.clamp(xr.0, xr.1), y.clamp(yr.0, yr.1)];
    let i = pts.iter().position(|q| q[0] > p[0]).unwrap_or(pts.len());
    pts.insert(i, p);
    i
}

/// Removes point `i` unless only two points are left; returns whether it did.
pub fn remove_point(pts: &mut Vec<[f64; 2]>, i: usize) -> bool {
    if pts.len() <= 2 || i >= pts.len() {
        return false;
    }
    pts.remove(i);
    true
}

/// Draws the graph of `pts` (abscissa range `xr`, ordinate range `yr`) and lets the pointer
/// edit it; `name` identifies it (and labels its points for accessibility).
pub fn curve_editor(ui: &mut egui::Ui, name: &str, pts: &mut Vec<[f64; 2]>, xr: (f64, f64), yr: (f64, f64)) -> CurveResponse {
    let mut out = CurveResponse::default();
    let width = ui.available_width().clamp(200.0, GRAPH_SIZE.x);
    let (rect, bg) = ui.allocate_exact_size(egui::vec2(width, GRAPH_SIZE.y), egui::Sense::click());
    let plot = rect.shrink2(egui::vec2(30.0, 12.0));
    let to_screen = |p: [f64; 2]| egui::pos2(plot.left() + ((p[0] - xr.0) / (xr.1 - xr.0)) as f32 * plot.width(), plot.bottom() - ((p[1] - yr.0) / (yr.1 - yr.0)) as f32 * plot.height());
    let to_value = |s: egui::Pos2| [xr.0 + ((s.x - plot.left()) / plot.width()) as f64 * (xr.1 - xr.0), yr.0 + ((plot.bottom() - s.y) / plot.height()) as f64 * (yr.1 - yr.0)];
    let painter = ui.painter_at(rect);
    let visuals = ui.visuals();
    painter.rect_filled(rect, 3.0, visuals.extreme_bg_color);
    let grid = visuals.weak_text_color().gamma_multiply(0.35);
    let step = if xr.1 - xr.0 > 20.0 { 5.0 } else { 1.0 };
    let mut x = xr.0;
    while x <= xr.1 + 1e-9 {
        let sx = to_screen([x, yr.0]).x;
        painter.line_segment([egui::pos2(sx, plot.top()), egui::pos2(sx, plot.bottom())], egui::Stroke::new(1.0, grid));
        x += step;
    }
    let font = egui::FontId::monospace(10.0);
    let tc = visuals.weak_text_color();
    painter.text(egui::pos2(rect.left() + 2.0, plot.top()), egui::Align2::LEFT_CENTER, format!("{}", yr.1), font.clone(), tc);
    painter.text(egui::pos2(rect.left() + 2.0, plot.bottom()), egui::Align2::LEFT_CENTER, format!("{}", yr.0), font.clone(), tc);
    painter.text(egui::pos2(plot.right(), rect.bottom() - 1.0), egui::Align2::RIGHT_BOTTOM, format!("{} {}", if xr.1 > 20.0 { "Weibull order w" } else { "Gravelius order g" }, xr.1), font.clone(), tc);
    painter.text(egui::pos2(plot.left(), rect.bottom() - 1.0), egui::Align2::LEFT_BOTTOM, format!("{}", xr.0), font, tc);
    // the line: constant beyond the ends, as the model evaluates it
    let mut line: Vec<egui::Pos2> = Vec::with_capacity(pts.len() + 2);
    if let (Some(f), Some(l)) = (pts.first(), pts.last()) {
        line.push(to_screen([xr.0, f[1]]));
        line.extend(pts.iter().map(|p| to_screen(*p)));
        line.push(to_screen([xr.1, l[1]]));
    }
    painter.add(egui::Shape::line(line, egui::Stroke::new(2.0, egui::Color32::from_rgb(90, 170, 230))));
    let mut remove = None;
    for i in 0..pts.len() {
        let c = to_screen(pts[i]);
        let id = egui::Id::unique(("curve point", name, i));
        let r = ui.interact(egui::Rect::from_center_size(c, egui::vec2(14.0, 14.0)), id, egui::Sense::click_and_drag());
        let label = point_label(name, i);
        r.widget_info(|| egui::WidgetInfo::labeled(egui::Role::Button, true, label.clone()));
        if r.hovered() || r.dragged() {
            out.hovered_point = Some(i);
        }
        if r.dragged() {
            let d = r.drag_delta();
            if d != egui::Vec2::ZERO {
                let v = to_value(c + d);
                move_point(pts, i, v[0], v[1], xr, yr);
                out.changed = true;
                out.started |= r.drag_started();
            }
        }
        if r.secondary_clicked() {
            remove = Some(i);
        }
        let r = r.on_hover_text(format!("{}: ({:.3}, {:.4}): drag to move, right-click to remove", label, pts[i][0], pts[i][1]));
        let hot = r.hovered() || r.dragged();
        painter.circle(to_screen(pts[i]), if hot { 6.0 } else { 4.5 }, if hot { egui::Color32::from_rgb(255, 60, 190) } else { egui::Color32::from_rgb(230, 230, 240) }, egui::Stroke::new(1.0, egui::Color32::BLACK));
    }
    if let Some(i) = remove {
        if remove_point(pts, i) {
            out.changed = true;
            out.started = true;
        }
    }
    if bg.double_clicked() {
        if let Some(p) = bg.interact_pointer_pos() {
            let v = to_value(p);
            add_point(pts, v[0], v[1], xr, yr);
            out.changed = true;
            out.started = true;
        }
    }
    out.hovered = bg.hovered() || out.hovered_point.is_some();
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn points_stay_ordered_and_in_bounds() {
        let mut p = vec![[0.0, 0.75], [7.0, 0.8], [15.0, 0.9]];
        move_point(&mut p, 1, 20.0, 3.0, (0.0, 15.0), (0.5, 1.0));
        assert_eq!(p[1], [15.0, 1.0], "clamped to the right neighbour and the ordinate bound");
        move_point(&mut p, 0, -3.0, 0.1, (0.0, 15.0), (0.5, 1.0));
        assert_eq!(p[0], [0.0, 0.5]);
        let i = add_point(&mut p, 3.0, 0.6, (0.0, 15.0), (0.5, 1.0));
        assert_eq!(i, 1);
        assert_eq!(p.len(), 4);
        assert!(p.windows(2).all(|w| w[0][0] <= w[1][0]));
        assert!(remove_point(&mut p, 1) && remove_point(&mut p, 1));
        assert!(!remove_point(&mut p, 0), "two points stay");
    }
}
