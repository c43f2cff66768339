//! The viewpoint sphere: an icosahedron subdivided `level` times (12, 42, 162, 642, 2562 points),
//! and its axes, one per antipodal pair, by canonical direction.

use std::collections::HashMap;

use crate::geometry::{canonical, normalize};

/// The highest subdivision level offered.
pub const MAX_LEVEL: usize = 4;

/// The icosphere's vertices: the icosahedron (0, ±1, ±φ) and cyclic permutations, normalized,
/// each triangle split into four `level` times with new vertices normalized.
pub fn icosphere(level: usize) -> Vec<[f64; 3]> {
    mesh(level).0
}

/// The icosphere's vertices (as [`icosphere`] gives them) and its triangles, by vertex index
/// (20, 80, 320, … of them), to draw it as the paper's Fig. 1a does.
pub fn mesh(level: usize) -> (Vec<[f64; 3]>, Vec<[usize; 3]>) {
    let phi = f64::midpoint(1.0, 5f64.sqrt());
    let mut points: Vec<[f64; 3]> = [
        [-1.0, phi, 0.0],
        [1.0, phi, 0.0],
        [-1.0, -phi, 0.0],
        [1.0, -phi, 0.0],
        [0.0, -1.0, phi],
        [0.0, 1.0, phi],
        [0.0, -1.0, -phi],
        [0.0, 1.0, -phi],
        [phi, 0.0, -1.0],
        [phi, 0.0, 1.0],
        [-phi, 0.0, -1.0],
        [-phi, 0.0, 1.0],
    ]
    .iter()
    .map(|&p| normalize(p).expect("icosahedron vertices are not zero"))
    .collect();
    let mut faces: Vec<[usize; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..level {
        let mut middle: HashMap<(usize, usize), usize> = HashMap::new();
        let mut mid = |a: usize, b: usize, points: &mut Vec<[f64; 3]>| {
            *middle.entry((a.min(b), a.max(b))).or_insert_with(|| {
                let (p, q) = (points[a], points[b]);
                points.push(
                    normalize(std::array::from_fn(|k| p[k] + q[k])).expect("no antipodal edge"),
                );
                points.len() - 1
            })
        };
        faces = faces
            .iter()
            .flat_map(|&[a, b, c]| {
                let ab = mid(a, b, &mut points);
                let bc = mid(b, c, &mut points);
                let ca = mid(c, a, &mut points);
                [[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]
            })
            .collect();
    }
    (points, faces)
}

/// One canonical direction per antipodal pair of the icosphere's vertices, in order of first
/// appearance (half the vertices: 6, 21, 81, 321, 1281).
pub fn axes(level: usize) -> Vec<[f64; 3]> {
    let mut seen = std::collections::HashSet::new();
    icosphere(level)
        .into_iter()
        .map(canonical)
        .filter(|d| seen.insert(d.map(|c| (c * 1e9).round() as i64)))
        .collect()
}

/// The angle between neighbouring viewpoints at `level`, in degrees (63.4° at level 0).
pub fn spacing_degrees(level: usize) -> f64 {
    // The icosahedron's edge subtends acos(1/√5); each subdivision roughly halves it.
    (1.0 / 5f64.sqrt()).acos().to_degrees() / f64::from(1u32 << level)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::dot;

    #[test]
    fn vertex_and_axis_counts() {
        for (level, n) in [(0, 12), (1, 42), (2, 162), (3, 642), (4, 2562)] {
            let pts = icosphere(level);
            assert_eq!(pts.len(), n, "level {level}");
            assert_eq!(axes(level).len(), n / 2, "level {level}");
            for p in &pts {
                assert!((dot(*p, *p) - 1.0).abs() < 1e-12);
            }
        }
    }

    #[test]
    fn the_mesh_is_closed() {
        for (level, faces) in [(0, 20), (1, 80), (2, 320)] {
            let (points, f) = mesh(level);
            assert_eq!(f.len(), faces);
            // Euler: V - E + F = 2, every edge shared by two triangles.
            let mut edges = std::collections::HashMap::new();
            for t in &f {
                for k in 0..3 {
                    let (a, b) = (t[k], t[(k + 1) % 3]);
                    *edges.entry((a.min(b), a.max(b))).or_insert(0) += 1;
                }
            }
            assert!(edges.values().all(|&n| n == 2), "level {level}");
            assert_eq!(points.len() + f.len(), edges.len() + 2, "level {level}");
        }
    }

    #[test]
    fn level_one_holds_the_coordinate_axes() {
        let a = axes(1);
        for e in [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]] {
            assert!(a.iter().any(|d| dot(*d, e) > 1.0 - 1e-12), "{e:?} missing");
        }
    }

    #[test]
    fn icosahedron_edges_are_equal() {
        let p = icosphere(0);
        let mut lengths: Vec<f64> = Vec::new();
        for a in 0..12 {
            for b in a + 1..12 {
                let d = dot(p[a], p[b]);
                if d > 0.4 {
                    lengths.push(d);
                }
            }
        }
        assert_eq!(lengths.len(), 30, "30 edges");
        assert!(
            lengths
                .iter()
                .all(|d| (d - 1.0 / 5f64.sqrt()).abs() < 1e-12)
        );
    }

    #[test]
    fn every_axis_is_canonical() {
        for d in axes(2) {
            assert_eq!(canonical(d), d);
        }
    }
}
