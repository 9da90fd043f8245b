//! Merging affinity propagation's small subgroups into their neighbours (the
//! project's [`Similarity::Local`](super::subgroups::Similarity) variant of
//! formation-transform section 3.4; the paper has no such step).
//!
//! Affinity propagation on the Delaunay ring (Frey & Dueck 2007 with a sparse
//! similarity) finds many small local subgroups: an exemplar can only gather agents
//! within a few hops. A subgroup a user would call one is larger, so the smallest
//! subgroup below [`min_group_size`] joins, one at a time, the neighbouring subgroup
//! (one sharing a Delaunay edge of the sources) with which it shares the most
//! edges (the longest border: merged subgroups stay compact), among equals the one
//! whose shared edges change their length least between the source and the target
//! formation (eq. 20 averaged on those edges). Subgroups stay connected in the
//! source triangulation, hence spatially coherent.

/// Agents per `√n` of the smallest subgroup kept by the merge.
///
/// With it the subgroups hold at least `1.5·√n` agents (15 at 100 agents, 26 at
/// 300, 48 at 1,000, 68 at 2,000), so they number at most `√n / 1.5` (6, 11, 20,
/// 29): the count grows slowly with the crowd, and a subgroup is large enough that
/// most of its agents have their nearest neighbour inside it. With `1.0·√n` the
/// shipped pairs had locality 0.77–0.84 at 100 and 300 agents; with 1.5 every one
/// has ≥ 0.8 at 100 to 2,000 agents (`subgroups_shipped.rs`).
pub const MIN_SIZE_PER_SQRT_N: f64 = 1.5;

/// The smallest subgroup `merge_small` keeps in a crowd of `n`:
/// `⌈MIN_SIZE_PER_SQRT_N·√n⌉`, within `1..=n` (1 for no agent).
pub fn min_group_size(n: usize) -> usize {
    ((MIN_SIZE_PER_SQRT_N * (n as f64).sqrt()).ceil() as usize).clamp(1, n.max(1))
}

/// Merges subgroups smaller than `min_size` into neighbouring ones (module
/// documentation) until none is left or one subgroup remains. `edges`: the
/// adjacency of the agents (the Delaunay edges of the sources), each `(i, k,
/// s(i, k))` with eq. 20's similarity `−Δdis` (−m²); `group_of[i]` in
/// `0..exemplars.len()`, updated; `exemplars` keeps the absorbing subgroups'
/// exemplars, renumbered in their order.
///
/// The smallest subgroup goes first (the lowest index among equals); it joins the
/// neighbour sharing the most Delaunay edges with it, among equals the one with the
/// largest mean of eq. 20's `−Δdis` over the shared edges (whose edges to it deform
/// least), then the lowest index. A subgroup without a neighbour (its agents all at
/// one point) stays.
///
/// # Complexity
/// `O(merges · (edges + n))`.
pub fn merge_small(
    edges: &[(u32, u32, f64)],
    group_of: &mut [u32],
    exemplars: &mut Vec<u32>,
    min_size: usize,
) {
    let groups = exemplars.len();
    let n = group_of.len();
    if groups <= 1 || n == 0 {
        return;
    }
    let mut size = vec![0usize; groups];
    for &g in group_of.iter() {
        size[g as usize] += 1;
    }
    let mut alive = groups;
    let mut stuck = vec![false; groups];
    // (neighbour, Σ −Δdis, shared edges)
    let mut near: Vec<(u32, f64, usize)> = Vec::new();
    while alive > 1 {
        let Some(g) = (0..groups)
            .filter(|&g| size[g] > 0 && size[g] < min_size && !stuck[g])
            .min_by_key(|&g| (size[g], g))
        else {
            break;
        };
        near.clear();
        for &(i, k, d) in edges {
            let (gi, gk) = (group_of[i as usize], group_of[k as usize]);
            let h = match (gi as usize == g, gk as usize == g) {
                (true, false) => gk,
                (false, true) => gi,
                _ => continue,
            };
            match near.iter_mut().find(|x| x.0 == h) {
                Some(x) => {
                    x.1 += d;
                    x.2 += 1;
                }
                None => near.push((h, d, 1)),
            }
        }
        let best = near.iter().copied().max_by(|a, b| {
            a.2.cmp(&b.2)
                .then((a.1 / a.2 as f64).total_cmp(&(b.1 / b.2 as f64)))
                .then(b.0.cmp(&a.0))
        });
        let Some((h, _, _)) = best else {
            stuck[g] = true;
            continue;
        };
        for x in group_of.iter_mut().filter(|x| **x as usize == g) {
            *x = h;
        }
        size[h as usize] += size[g];
        size[g] = 0;
        alive -= 1;
    }
    let mut renum = vec![u32::MAX; groups];
    let mut kept = Vec::with_capacity(alive);
    for g in 0..groups {
        if size[g] > 0 {
            renum[g] = kept.len() as u32;
            kept.push(exemplars[g]);
        }
    }
    for x in group_of.iter_mut() {
        *x = renum[*x as usize];
    }
    *exemplars = kept;
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::Vec2;

    /// The pairs of `s` at most `reach` apart, with eq. 20's similarity to `t`.
    fn edges(s: &[Vec2], t: &[Vec2], reach: f64) -> Vec<(u32, u32, f64)> {
        let w = |p: Vec2, q: Vec2| (p.x - q.x).abs() + (p.y - q.y).abs();
        let mut e = Vec::new();
        for i in 0..s.len() {
            for k in i + 1..s.len() {
                if (s[i] - s[k]).norm() <= reach {
                    let d = w(s[i], s[k]) - w(t[i], t[k]);
                    e.push((i as u32, k as u32, -(d * d)));
                }
            }
        }
        e
    }

    #[test]
    fn min_size_grows_with_the_square_root() {
        assert_eq!(min_group_size(0), 1);
        assert_eq!(min_group_size(1), 1);
        assert_eq!(min_group_size(100), 15);
        assert_eq!(min_group_size(300), 26);
        assert_eq!(min_group_size(2000), 68);
        assert_eq!(min_group_size(4), 3);
    }

    /// A 6 × 4 grid in three column bands (columns 0, 1–3 and 4–5: 4, 12 and 8
    /// agents): the small left band joins the middle; the right one too when the
    /// floor is above it; the exemplars follow.
    #[test]
    fn small_subgroups_join_a_neighbour() {
        let mut s = Vec::new();
        let mut group_of = Vec::new();
        for x in 0..6 {
            for y in 0..4 {
                s.push(Vec2::new(x as f64 + 0.01 * y as f64, y as f64));
                group_of.push(match x {
                    0 => 0u32,
                    4 | 5 => 2,
                    _ => 1,
                });
            }
        }
        let t = s.clone();
        let mut g = group_of.clone();
        let mut ex = vec![0, 10, 22];
        merge_small(&edges(&s, &t, 1.1), &mut g, &mut ex, 5);
        assert_eq!(ex, vec![10, 22]);
        assert!(g[..16].iter().all(|&x| x == 0) && g[16..].iter().all(|&x| x == 1));
        let mut g = group_of.clone();
        let mut ex = vec![0, 10, 22];
        merge_small(&edges(&s, &t, 1.1), &mut g, &mut ex, 9);
        assert_eq!((ex, g), (vec![10], vec![0; 24]));
        // Already large enough: nothing changes.
        let mut g = group_of.clone();
        let mut ex = vec![0, 10, 22];
        merge_small(&edges(&s, &t, 1.1), &mut g, &mut ex, 1);
        assert_eq!((ex, g), (vec![0, 10, 22], group_of));
    }

    /// A small subgroup between two larger ones, sharing as many edges with each,
    /// joins the one whose edges to it keep their length (eq. 20), not the one they
    /// stretch.
    #[test]
    fn the_least_deformed_neighbour_absorbs() {
        let s: Vec<Vec2> = (0..9)
            .map(|k| Vec2::new(k as f64, 0.1 * (k % 2) as f64))
            .collect();
        // Agents 0–3 stay, 4 (the small subgroup) stays, 5–8 move 3 m right.
        let t: Vec<Vec2> = s
            .iter()
            .enumerate()
            .map(|(k, p)| *p + Vec2::new(if k >= 5 { 3.0 } else { 0.0 }, 0.0))
            .collect();
        let mut g = vec![0, 0, 0, 0, 1, 2, 2, 2, 2];
        let mut ex = vec![1, 4, 6];
        merge_small(&edges(&s, &t, 1.1), &mut g, &mut ex, 2);
        assert_eq!(ex, vec![1, 6]);
        assert_eq!(g, vec![0, 0, 0, 0, 0, 1, 1, 1, 1]);
    }
}
