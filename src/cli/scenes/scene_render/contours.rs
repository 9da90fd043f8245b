//! Iso-time contours (marching squares).

/// Marching squares over a lattice of values (`+inf` = no value): the segments of
/// the iso-line at `level`, in lattice coordinates (corner `(i, j)` at `(i, j)`).
pub fn iso_segments(vals: &[f64], nx: usize, ny: usize, level: f64) -> Vec<[(f64, f64); 2]> {
    let mut out = Vec::new();
    if nx < 2 || ny < 2 {
        return out;
    }
    let at = |i: usize, j: usize| vals[j * nx + i];
    for j in 0..ny - 1 {
        for i in 0..nx - 1 {
            // Corners a (i, j), b (i+1, j), c (i+1, j+1), d (i, j+1).
            let v = [at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)];
            if v.iter().any(|x| !x.is_finite()) {
                continue;
            }
            let pos = [
                (i as f64, j as f64),
                (i as f64 + 1.0, j as f64),
                (i as f64 + 1.0, j as f64 + 1.0),
                (i as f64, j as f64 + 1.0),
            ];
            let below = v.map(|x| x < level);
            // Edge k joins corners k and k+1: 0 top, 1 right, 2 bottom, 3 left.
            let cross = |k: usize| -> Option<(f64, f64)> {
                let (a, b) = (k, (k + 1) % 4);
                if below[a] == below[b] {
                    return None;
                }
                let f = ((level - v[a]) / (v[b] - v[a])).clamp(0.0, 1.0);
                Some((
                    pos[a].0 + (pos[b].0 - pos[a].0) * f,
                    pos[a].1 + (pos[b].1 - pos[a].1) * f,
                ))
            };
            let e: Vec<(usize, (f64, f64))> =
                (0..4).filter_map(|k| cross(k).map(|p| (k, p))).collect();
            match e.len() {
                2 => out.push([e[0].1, e[1].1]),
                4 => {
                    let centre_below = (v.iter().sum::<f64>() / 4.0) < level;
                    let p = |k: usize| e[k].1;
                    if centre_below == below[0] {
                        // a and c connect through the centre: cut off b and d.
                        out.push([p(0), p(1)]);
                        out.push([p(2), p(3)]);
                    } else {
                        out.push([p(3), p(0)]);
                        out.push([p(1), p(2)]);
                    }
                }
                _ => {}
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn iso_segments_of_a_plane_are_one_straight_line() {
        // v = x on a 3 × 3 lattice: the level 0.5 is the line x = 0.5.
        let vals = [0.0, 1.0, 2.0, 0.0, 1.0, 2.0, 0.0, 1.0, 2.0];
        let segs = iso_segments(&vals, 3, 3, 0.5);
        assert_eq!(segs.len(), 2);
        for s in segs {
            assert!((s[0].0 - 0.5).abs() < 1e-12 && (s[1].0 - 0.5).abs() < 1e-12);
        }
        // A missing corner drops the squares around it.
        let mut holes = vals;
        holes[3] = f64::INFINITY;
        assert!(iso_segments(&holes, 3, 3, 0.5).is_empty());
    }
}
