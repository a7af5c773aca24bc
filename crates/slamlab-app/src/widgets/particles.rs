//! Particle clouds (and a pose graph's thousands of nodes and edges) drawn as one mesh.
//!
//! A cloud of 5,000 particles drawn as 5,000 line segments and 5,000 circles
//! is 10,000 shapes for egui to tessellate every frame, each anti-aliased
//! with feathered edges. A particle is a few pixels across, so a plain
//! triangle says as much: [`ParticleMesh`] collects one dart per particle (and
//! a small square per landmark mean) into a single [`egui::Mesh`], which egui
//! hands to the GPU as it is. The Cartographer lesson draws its nodes and
//! constraints the same way ([`ParticleMesh::segment`]).

use super::map_canvas::finite;
use egui::{Color32, Mesh, Pos2, Vec2, vec2};

/// Darts and dots collected into one mesh, painted with [`ParticleMesh::paint`].
#[derive(Debug, Default)]
pub struct ParticleMesh {
    mesh: Mesh,
}

impl ParticleMesh {
    /// An empty mesh with room for `darts` particles.
    pub fn with_capacity(darts: usize) -> Self {
        let mut mesh = Mesh::default();
        mesh.vertices.reserve(3 * darts);
        mesh.indices.reserve(3 * darts);
        Self { mesh }
    }

    /// A particle at screen point `at` heading along the unit screen vector
    /// `dir`: a narrow dart `length` points long whose tip points the way the
    /// particle faces and whose tail sits on its position. Skipped when `at`
    /// is not finite.
    pub fn dart(&mut self, at: Pos2, dir: Vec2, length: f32, color: Color32) {
        if !finite(at) || !dir.x.is_finite() || !dir.y.is_finite() {
            return;
        }
        let side = vec2(-dir.y, dir.x) * (0.3 * length).max(1.2);
        let tip = at + dir * length;
        let tail = at - dir * (0.15 * length);
        self.triangle(tip, tail + side, tail - side, color);
    }

    /// A filled square `2 half` points wide centred on `at` (a landmark mean of
    /// one particle's map). Skipped when `at` is not finite.
    pub fn dot(&mut self, at: Pos2, half: f32, color: Color32) {
        if !finite(at) {
            return;
        }
        let base = self.mesh.vertices.len() as u32;
        for corner in [
            vec2(-half, -half),
            vec2(half, -half),
            vec2(half, half),
            vec2(-half, half),
        ] {
            self.mesh.colored_vertex(at + corner, color);
        }
        self.mesh.add_triangle(base, base + 1, base + 2);
        self.mesh.add_triangle(base, base + 2, base + 3);
    }

    /// A straight line from `a` to `b`, `width` points wide, as one quad without
    /// anti-aliased edges (a graph's thousands of edges). A line thinner than a
    /// point is drawn one point wide and as much fainter, which looks the same.
    /// Skipped when an end is not finite or the two coincide.
    pub fn segment(&mut self, a: Pos2, b: Pos2, width: f32, color: Color32) {
        if !finite(a) || !finite(b) || !width.is_finite() {
            return;
        }
        let along = b - a;
        let length = along.length();
        if length <= f32::EPSILON {
            return;
        }
        let (width, color) = if width < 1.0 {
            (1.0, color.gamma_multiply(width.max(0.0)))
        } else {
            (width, color)
        };
        let side = vec2(-along.y, along.x) * (0.5 * width / length);
        let base = self.mesh.vertices.len() as u32;
        for p in [a + side, b + side, b - side, a - side] {
            self.mesh.colored_vertex(p, color);
        }
        self.mesh.add_triangle(base, base + 1, base + 2);
        self.mesh.add_triangle(base, base + 2, base + 3);
    }

    fn triangle(&mut self, a: Pos2, b: Pos2, c: Pos2, color: Color32) {
        let base = self.mesh.vertices.len() as u32;
        self.mesh.colored_vertex(a, color);
        self.mesh.colored_vertex(b, color);
        self.mesh.colored_vertex(c, color);
        self.mesh.add_triangle(base, base + 1, base + 2);
    }

    /// How many triangles the mesh holds.
    pub fn triangles(&self) -> usize {
        self.mesh.indices.len() / 3
    }

    /// Paints the whole mesh at once (nothing for an empty one).
    pub fn paint(self, painter: &egui::Painter) {
        if !self.mesh.is_empty() {
            painter.add(egui::Shape::mesh(self.mesh));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_dart_points_the_way_the_particle_faces() {
        let mut m = ParticleMesh::with_capacity(1);
        m.dart(Pos2::new(10.0, 10.0), vec2(1.0, 0.0), 8.0, Color32::RED);
        assert_eq!(m.triangles(), 1);
        let v = &m.mesh.vertices;
        assert_eq!(v[0].pos, Pos2::new(18.0, 10.0), "the tip, 8 points ahead");
        // The tail is behind the position and symmetric about the heading.
        assert!(v[1].pos.x < 10.0 && v[2].pos.x < 10.0);
        assert!((v[1].pos.y - 10.0 + v[2].pos.y - 10.0).abs() < 1e-5);
    }

    #[test]
    fn non_finite_particles_are_left_out() {
        let mut m = ParticleMesh::with_capacity(2);
        m.dart(Pos2::new(f32::NAN, 0.0), vec2(1.0, 0.0), 8.0, Color32::RED);
        m.dart(
            Pos2::new(0.0, 0.0),
            vec2(f32::INFINITY, 0.0),
            8.0,
            Color32::RED,
        );
        m.dot(Pos2::new(0.0, f32::INFINITY), 1.0, Color32::RED);
        assert_eq!(m.triangles(), 0);
        m.dot(Pos2::new(1.0, 1.0), 1.0, Color32::RED);
        assert_eq!(m.triangles(), 2);
    }
}
