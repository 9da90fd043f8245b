//! The K nearest library gestures of a gesture under the distance of gesture-driven
//! eq. 12, their inverse-distance weights (eq. 18), and weighted voting (section 8.2).
//!
//! The search returns exactly what a brute-force scan returns (same entries, same
//! distances, ties broken by entry index), only faster:
//! - every entry gets a cheap lower bound of eq. 12, `Σ w_f max(LB_Kim_f, LB_Keogh_f)`
//!   (the Keogh envelopes of the entries are built once, in [`GestureIndex::new`], for
//!   the index's band; another band uses the query's envelope instead);
//! - entries are visited in order of that bound, and the scan stops at the first bound
//!   above the current K-th distance;
//! - each feature's DTW is abandoned as soon as it alone, with what is already summed
//!   and the other features' bounds, exceeds the K-th distance.
//!
//! A relative slack of [`PRUNE_SLACK`] on every comparison keeps rounding in the
//! bounds from ever pruning an entry that a brute-force scan would keep.
//!
//! An index may also hold every entry's physical features (`physical.rs`) with their
//! weights: the distance is then `w₁₂ · eq. 12 + Σ_k w_k │a_k − b_k│`. The physical
//! part is cheap and exact, so it is added to every entry's bound as it is and the
//! search stays exact. An index without them (or with
//! [`PhysicalWeights::BASELINE`]) is the paper's eq. 12 alone.

use super::dtw::{feature_dtw, lb_keogh, lb_kim, weighted_sum, Dtw, Envelope, Weights};
use super::features::GestureFeatures;
use super::library::T_H;
use super::physical::{PhysicalFeatures, PhysicalWeights};
use std::cmp::Ordering;

/// Relative slack applied to the K-th distance before a bound is compared with it.
pub const PRUNE_SLACK: f64 = 1e-9;

/// How to search.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct SearchParams {
    /// How many neighbours (gesture-driven section 7.1: K = 10).
    pub k: usize,
    /// The feature weights of eq. 12.
    pub weights: Weights,
    /// Sakoe–Chiba band radius of every DTW (`None`: unconstrained, as in the paper).
    pub band: Option<usize>,
}

impl Default for SearchParams {
    fn default() -> SearchParams {
        SearchParams {
            k: 10,
            weights: Weights::default(),
            band: None,
        }
    }
}

/// A neighbour of a query: which entry, how far (eq. 12), and its weight (eq. 18).
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Neighbour {
    /// Index of the entry in the [`GestureIndex`].
    pub entry: usize,
    /// Distance to the query (eq. 12).
    pub distance: f64,
    /// Inverse-distance weight among the K (eq. 18); the K weights sum to 1.
    pub weight: f64,
}

/// The envelopes of one gesture's four feature sequences.
#[derive(Clone, Debug, Default)]
struct Envelopes([Envelope; 4]);

impl Envelopes {
    fn fill(&mut self, g: &GestureFeatures, band: Option<usize>) {
        self.0[0].fill(&g.centroid, T_H, band);
        self.0[1].fill(&g.spread, T_H, band);
        self.0[2].fill(&g.rotation, T_H, band);
        self.0[3].fill(&g.mobb, T_H, band);
    }

    fn of(g: &GestureFeatures, band: Option<usize>) -> Envelopes {
        let mut e = Envelopes::default();
        e.fill(g, band);
        e
    }
}

/// LB_Keogh of feature `f` of `a` against envelopes.
fn keogh(a: &GestureFeatures, env: &Envelopes, f: usize) -> f64 {
    match f {
        0 => lb_keogh(&a.centroid, &env.0[0], f64::INFINITY),
        1 => lb_keogh(&a.spread, &env.0[1], f64::INFINITY),
        2 => lb_keogh(&a.rotation, &env.0[2], f64::INFINITY),
        _ => lb_keogh(&a.mobb, &env.0[3], f64::INFINITY),
    }
}

fn kim(a: &GestureFeatures, b: &GestureFeatures, f: usize) -> f64 {
    match f {
        0 => lb_kim(&a.centroid, &b.centroid),
        1 => lb_kim(&a.spread, &b.spread),
        2 => lb_kim(&a.rotation, &b.rotation),
        _ => lb_kim(&a.mobb, &b.mobb),
    }
}

/// Library gestures' features with their LB_Keogh envelopes, and optionally their
/// physical features and the weights of the combined distance.
#[derive(Clone, Debug)]
pub struct GestureIndex {
    entries: Vec<GestureFeatures>,
    envelopes: Vec<Envelopes>,
    band: Option<usize>,
    physical: Vec<PhysicalFeatures>,
    physical_weights: PhysicalWeights,
}

impl GestureIndex {
    /// An index with envelopes for unbanded search (the default).
    pub fn new(entries: Vec<GestureFeatures>) -> GestureIndex {
        GestureIndex::with_band(entries, None)
    }

    /// An index with envelopes for searches in a Sakoe–Chiba band of radius `band`
    /// (other bands still search correctly, with the query's envelope).
    pub fn with_band(entries: Vec<GestureFeatures>, band: Option<usize>) -> GestureIndex {
        let envelopes = entries.iter().map(|g| Envelopes::of(g, band)).collect();
        GestureIndex {
            physical: vec![PhysicalFeatures::default(); entries.len()],
            entries,
            envelopes,
            band,
            physical_weights: PhysicalWeights::BASELINE,
        }
    }

    /// An index searched by the combined distance of eq. 12 and the physical
    /// features (module doc). `physical` has one vector per entry (missing ones are
    /// unknown).
    pub fn with_physical(
        entries: Vec<GestureFeatures>,
        mut physical: Vec<PhysicalFeatures>,
        weights: PhysicalWeights,
        band: Option<usize>,
    ) -> GestureIndex {
        physical.resize(entries.len(), PhysicalFeatures::default());
        GestureIndex {
            physical,
            physical_weights: weights,
            ..GestureIndex::with_band(entries, band)
        }
    }

    /// The weights of the combined distance.
    pub fn physical_weights(&self) -> &PhysicalWeights {
        &self.physical_weights
    }

    /// Entry `i`'s physical features.
    pub fn physical(&self, i: usize) -> Option<&PhysicalFeatures> {
        self.physical.get(i)
    }

    /// Entries.
    pub fn len(&self) -> usize {
        self.entries.len()
    }

    /// Whether there is no entry.
    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }

    /// Entry `i`'s features.
    pub fn get(&self, i: usize) -> Option<&GestureFeatures> {
        self.entries.get(i)
    }

    /// The band its envelopes were built for.
    pub fn band(&self) -> Option<usize> {
        self.band
    }
}

/// How much work the last search did (for benchmarks and reports).
#[derive(Copy, Clone, Debug, Default, PartialEq, Eq)]
pub struct SearchStats {
    /// Entries whose distance was computed in full.
    pub computed: usize,
    /// Entries whose DTW was abandoned part way.
    pub abandoned: usize,
    /// Entries never looked at beyond their lower bound.
    pub pruned: usize,
}

/// A reusable searcher: its buffers grow to the largest index searched and are then
/// reused, so a search allocates nothing in steady state.
#[derive(Clone, Debug, Default)]
pub struct Searcher {
    dtw: Dtw,
    query_env: Envelopes,
    /// Per entry: the lower bound of each feature's DTW.
    bounds: Vec<[f64; 4]>,
    /// `(weighted bound, entry)`, sorted.
    order: Vec<(f64, usize)>,
    best: Vec<Neighbour>,
    /// Per entry: the physical part of its distance.
    physical: Vec<f64>,
    stats: SearchStats,
}

/// The combined distance from its parts (one expression, so the search and the
/// brute force agree to the bit).
#[inline]
fn combined(scale12: f64, eq12: f64, physical: f64) -> f64 {
    if scale12 > 0.0 {
        scale12 * eq12 + physical
    } else {
        physical
    }
}

/// `(distance, entry)` order: nearer first, then lower index.
fn closer(a: (f64, usize), b: (f64, usize)) -> bool {
    a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)) == Ordering::Less
}

impl Searcher {
    /// A searcher.
    pub fn new() -> Searcher {
        Searcher::default()
    }

    /// The work done by the last search.
    pub fn stats(&self) -> SearchStats {
        self.stats
    }

    /// The `p.k` entries of `index` nearest to `query` (fewer when the index is
    /// smaller), nearest first, ties by entry index, with the weights of eq. 18.
    ///
    /// # Complexity
    ///
    /// At worst the brute force's `O(len · T_H²)`; in practice most entries are pruned
    /// by their bound or abandoned within a few DTW rows.
    pub fn search(
        &mut self,
        index: &GestureIndex,
        query: &GestureFeatures,
        p: &SearchParams,
    ) -> &[Neighbour] {
        self.search_with(index, query, &PhysicalFeatures::default(), p)
    }

    /// [`search`](Self::search) by the index's combined distance, with the query's
    /// physical features (unknown ones, and all of them with the baseline weights,
    /// count for nothing).
    pub fn search_with(
        &mut self,
        index: &GestureIndex,
        query: &GestureFeatures,
        query_physical: &PhysicalFeatures,
        p: &SearchParams,
    ) -> &[Neighbour] {
        self.best.clear();
        self.stats = SearchStats::default();
        let k = p.k.min(index.len());
        if k == 0 {
            return &self.best;
        }
        let pw = &index.physical_weights;
        let scale12 = pw.eq12;
        // With no weight on eq. 12 no DTW is needed: the physical part is exact.
        let w = if scale12 > 0.0 {
            p.weights.as_array()
        } else {
            [0.0; 4]
        };
        let own_env = index.band == p.band;
        if !own_env {
            self.query_env.fill(query, p.band);
        }
        self.bounds.clear();
        self.order.clear();
        self.physical.clear();
        for (e, g) in index.entries.iter().enumerate() {
            let mut lb = [0.0; 4];
            let mut total = 0.0;
            let phys = pw.distance(query_physical, &index.physical[e]);
            self.physical.push(phys);
            for f in 0..4 {
                if w[f] == 0.0 {
                    continue;
                }
                let keogh_f = if own_env {
                    keogh(query, &index.envelopes[e], f)
                } else {
                    keogh(g, &self.query_env, f)
                };
                lb[f] = kim(query, g, f).max(keogh_f);
                total += w[f] * lb[f];
            }
            self.bounds.push(lb);
            self.order.push((scale12 * total + phys, e));
        }
        self.order
            .sort_unstable_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        // Features by decreasing weight: the heaviest tighten the threshold soonest.
        let mut feats = [0usize, 1, 2, 3];
        feats.sort_by(|&a, &b| w[b].total_cmp(&w[a]).then(a.cmp(&b)));

        for oi in 0..self.order.len() {
            let (bound, e) = self.order[oi];
            let full = self.best.len() == k;
            let limit = if full {
                self.best[k - 1].distance * (1.0 + PRUNE_SLACK)
            } else {
                f64::INFINITY
            };
            if bound > limit {
                self.stats.pruned += self.order.len() - oi;
                break;
            }
            let lb = self.bounds[e];
            let phys = self.physical[e];
            // What eq. 12's weighted sum may reach before the entry is out.
            let limit12 = if scale12 > 0.0 {
                (limit - phys) / scale12
            } else {
                f64::INFINITY
            };
            let mut d = [0.0; 4];
            let mut acc = 0.0;
            let mut rest: f64 = feats.iter().map(|&f| w[f] * lb[f]).sum();
            let mut abandoned = false;
            for &f in &feats {
                if w[f] == 0.0 {
                    continue;
                }
                rest -= w[f] * lb[f];
                let max_f = if full {
                    Some(((limit12 - acc - rest.max(0.0)) / w[f]).max(0.0) * (1.0 + PRUNE_SLACK))
                } else {
                    None
                };
                d[f] = feature_dtw(&mut self.dtw, query, &index.entries[e], f, p.band, max_f);
                if d[f] == f64::INFINITY && max_f.is_some() {
                    abandoned = true;
                    break;
                }
                acc += w[f] * d[f];
            }
            if abandoned {
                self.stats.abandoned += 1;
                continue;
            }
            self.stats.computed += 1;
            let dist = combined(scale12, weighted_sum(&p.weights, &d), phys);
            if full
                && !closer(
                    (dist, e),
                    (self.best[k - 1].distance, self.best[k - 1].entry),
                )
            {
                continue;
            }
            if full {
                self.best.pop();
            }
            let at = self
                .best
                .partition_point(|n| closer((n.distance, n.entry), (dist, e)));
            self.best.insert(
                at,
                Neighbour {
                    entry: e,
                    distance: dist,
                    weight: 0.0,
                },
            );
        }
        inverse_distance_weights(&mut self.best);
        &self.best
    }
}

/// Sets the weights of eq. 18: `w_k = (1 / D_k) / Σ_j 1 / D_j`. Neighbours at
/// distance 0 (an exact match) share all the weight equally and the others get none.
pub fn inverse_distance_weights(neighbours: &mut [Neighbour]) {
    let exact = |d: f64| d == 0.0 || !(1.0 / d).is_finite();
    let n_exact = neighbours.iter().filter(|n| exact(n.distance)).count();
    if n_exact > 0 {
        for n in neighbours.iter_mut() {
            n.weight = if exact(n.distance) {
                1.0 / n_exact as f64
            } else {
                0.0
            };
        }
        return;
    }
    let total: f64 = neighbours.iter().map(|n| 1.0 / n.distance).sum();
    for n in neighbours.iter_mut() {
        n.weight = if total > 0.0 && total.is_finite() {
            (1.0 / n.distance) / total
        } else {
            0.0
        };
    }
}

/// The K nearest by computing every distance: what [`Searcher::search`] must equal.
pub fn brute_force(
    index: &GestureIndex,
    query: &GestureFeatures,
    p: &SearchParams,
) -> Vec<Neighbour> {
    brute_force_with(index, query, &PhysicalFeatures::default(), p)
}

/// [`brute_force`] by the index's combined distance: what
/// [`Searcher::search_with`] must equal.
pub fn brute_force_with(
    index: &GestureIndex,
    query: &GestureFeatures,
    query_physical: &PhysicalFeatures,
    p: &SearchParams,
) -> Vec<Neighbour> {
    let mut dtw = Dtw::new();
    let pw = &index.physical_weights;
    let mut all: Vec<Neighbour> = index
        .entries
        .iter()
        .enumerate()
        .map(|(e, g)| {
            let eq12 = if pw.eq12 > 0.0 {
                super::dtw::gesture_distance(&mut dtw, query, g, &p.weights, p.band)
            } else {
                0.0
            };
            Neighbour {
                entry: e,
                distance: combined(
                    pw.eq12,
                    eq12,
                    pw.distance(query_physical, &index.physical[e]),
                ),
                weight: 0.0,
            }
        })
        .collect();
    all.sort_by(|a, b| {
        a.distance
            .total_cmp(&b.distance)
            .then(a.entry.cmp(&b.entry))
    });
    all.truncate(p.k);
    inverse_distance_weights(&mut all);
    all
}

/// Weighted KNN voting (gesture-driven section 8.2): the class with the largest sum
/// of neighbour weights, and that sum (in `[0, 1]`). A tie goes to the class of the
/// nearest neighbour among the tied classes. `None` without neighbours.
///
/// Any class type: a library's [`ClassId`](super::library::ClassId), or a
/// generator's [`MotionClass`](super::library::MotionClass). No allocation: each
/// neighbour's class total is summed over the (at most K) neighbours.
pub fn vote<C: Copy + PartialEq>(
    neighbours: &[Neighbour],
    class_of: impl Fn(usize) -> C,
) -> Option<(C, f64)> {
    let total = |c: C| -> f64 {
        neighbours
            .iter()
            .filter(|n| class_of(n.entry) == c)
            .map(|n| n.weight)
            .sum()
    };
    // Neighbours are nearest first, so the first one whose class has the top total wins.
    let top = neighbours
        .iter()
        .map(|n| total(class_of(n.entry)))
        .fold(f64::NEG_INFINITY, f64::max);
    neighbours
        .iter()
        .map(|n| class_of(n.entry))
        .find(|&c| total(c) == top)
        // Rounding may sum ten weights to a hair over 1.
        .map(|c| (c, top.min(1.0)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::Vec2;
    use crate::gesture::library::MotionClass;
    use crate::rng::SplitMix64;
    use proptest::prelude::*;

    /// Features of a random smooth gesture: a few random harmonics per feature.
    fn random_features(rng: &mut SplitMix64) -> GestureFeatures {
        let mut wave = |scale: f64| {
            let (a, b, c) = (
                rng.uniform(-1.0, 1.0),
                rng.uniform(-1.0, 1.0),
                rng.uniform(0.5, 3.0),
            );
            move |t: usize| scale * (a + b * (c * t as f64 / T_H as f64).sin())
        };
        let (cx, cy, s, r, w, h) = (
            wave(0.5),
            wave(0.5),
            wave(0.3),
            wave(3.0),
            wave(0.3),
            wave(0.6),
        );
        GestureFeatures {
            centroid: std::array::from_fn(|t| Vec2::new(cx(t), cy(t))),
            spread: std::array::from_fn(|t| s(t).abs()),
            rotation: std::array::from_fn(r),
            mobb: std::array::from_fn(|t| Vec2::new(w(t).abs(), h(t).abs())),
        }
    }

    #[test]
    fn weights_of_eq_18() {
        let mut n = vec![
            Neighbour {
                entry: 0,
                distance: 1.0,
                weight: 0.0,
            },
            Neighbour {
                entry: 1,
                distance: 2.0,
                weight: 0.0,
            },
            Neighbour {
                entry: 2,
                distance: 4.0,
                weight: 0.0,
            },
        ];
        inverse_distance_weights(&mut n);
        let w: Vec<f64> = n.iter().map(|n| n.weight).collect();
        assert!(
            (w[0] - 4.0 / 7.0).abs() < 1e-15
                && (w[1] - 2.0 / 7.0).abs() < 1e-15
                && (w[2] - 1.0 / 7.0).abs() < 1e-15
        );
        n[1].distance = 0.0;
        n[2].distance = 0.0;
        inverse_distance_weights(&mut n);
        assert_eq!(
            n.iter().map(|n| n.weight).collect::<Vec<_>>(),
            vec![0.0, 0.5, 0.5]
        );
    }

    #[test]
    fn voting_sums_weights_per_class() {
        let nb = |entry: usize, weight: f64| Neighbour {
            entry,
            distance: 1.0 + 0.1 * entry as f64,
            weight,
        };
        let n = [nb(0, 0.3), nb(1, 0.25), nb(2, 0.3), nb(3, 0.15)];
        let class = |e: usize| {
            if e == 0 || e == 3 {
                MotionClass::Twist
            } else {
                MotionClass::Split
            }
        };
        let (c, w) = vote(&n, class).unwrap();
        assert_eq!(c, MotionClass::Split);
        assert!((w - 0.55).abs() < 1e-12);
        // A tie goes to the class of the nearest.
        let tie = |e: usize| {
            if e < 2 {
                MotionClass::Join
            } else {
                MotionClass::Expand
            }
        };
        let n2 = [nb(0, 0.375), nb(1, 0.125), nb(2, 0.25), nb(3, 0.25)];
        assert_eq!(vote(&n2, tie), Some((MotionClass::Join, 0.5)));
        assert_eq!(vote(&[], class), None);
    }

    #[test]
    fn an_exact_match_takes_all_the_weight_and_small_indices_win_ties() {
        let mut rng = SplitMix64::new(3);
        let mut entries: Vec<GestureFeatures> =
            (0..30).map(|_| random_features(&mut rng)).collect();
        entries[20] = entries[7].clone();
        let index = GestureIndex::new(entries.clone());
        let got = Searcher::new()
            .search(&index, &entries[20], &SearchParams::default())
            .to_vec();
        assert_eq!((got[0].entry, got[1].entry), (7, 20));
        assert_eq!((got[0].weight, got[1].weight), (0.5, 0.5));
        assert!(got[2..].iter().all(|n| n.weight == 0.0 && n.distance > 0.0));
        assert_eq!(got.len(), 10);
    }

    #[test]
    fn small_index_and_k_zero() {
        let mut rng = SplitMix64::new(4);
        let entries: Vec<GestureFeatures> = (0..3).map(|_| random_features(&mut rng)).collect();
        let index = GestureIndex::new(entries);
        let q = random_features(&mut rng);
        let mut s = Searcher::new();
        assert_eq!(s.search(&index, &q, &SearchParams::default()).len(), 3);
        assert!(s
            .search(
                &index,
                &q,
                &SearchParams {
                    k: 0,
                    ..SearchParams::default()
                }
            )
            .is_empty());
        assert!(s
            .search(&GestureIndex::new(vec![]), &q, &SearchParams::default())
            .is_empty());
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 40, rng_seed: proptest::test_runner::RngSeed::Fixed(15), ..ProptestConfig::default() })]
        #[test]
        fn pruned_search_equals_brute_force(
            seed in any::<u64>(),
            n in 1usize..80,
            k in 1usize..12,
            band in proptest::option::of(0usize..10),
            index_band in proptest::option::of(0usize..10),
            dup in any::<bool>(),
            ablate in 0usize..5,
            physical in 0usize..3,
        ) {
            let mut rng = SplitMix64::new(seed);
            let mut entries: Vec<GestureFeatures> = (0..n).map(|_| random_features(&mut rng)).collect();
            let query = if dup { entries[n / 2].clone() } else { random_features(&mut rng) };
            if dup && n > 3 {
                // Ties at distance 0 and at equal non-zero distances.
                entries[n - 1] = entries[n / 2].clone();
                entries[1] = entries[0].clone();
            }
            let mut w = Weights::default().as_array();
            if ablate < 4 {
                w[ablate] = 0.0;
            }
            let p = SearchParams { k, weights: Weights::from_array(w), band };
            if physical == 0 {
                let index = GestureIndex::with_band(entries, index_band);
                let want = brute_force(&index, &query, &p);
                let mut s = Searcher::new();
                let got = s.search(&index, &query, &p).to_vec();
                prop_assert_eq!(got, want);
            } else {
                // The combined distance, with eq. 12 weighted or (physical == 2) not
                // at all, and some features unknown.
                let phys = |rng: &mut SplitMix64| PhysicalFeatures {
                    values: std::array::from_fn(|_| {
                        if rng.unit() < 0.1 { f64::NAN } else { rng.uniform(-2.0, 2.0) }
                    }),
                };
                let ph: Vec<PhysicalFeatures> = (0..entries.len()).map(|_| phys(&mut rng)).collect();
                let q = phys(&mut rng);
                let weights = PhysicalWeights {
                    eq12: if physical == 2 { 0.0 } else { rng.uniform(0.1, 2.0) },
                    features: std::array::from_fn(|_| rng.uniform(0.0, 1.0)),
                };
                let index = GestureIndex::with_physical(entries, ph, weights, index_band);
                let want = brute_force_with(&index, &query, &q, &p);
                let mut s = Searcher::new();
                let got = s.search_with(&index, &query, &q, &p).to_vec();
                prop_assert_eq!(got, want);
            }
        }
    }
}
