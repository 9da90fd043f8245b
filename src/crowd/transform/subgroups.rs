//! Subgroups by affinity propagation (formation-transform section 3.4). CONTRACT ONLY.

use crate::crowd::assign::Cancel;
use crate::geom::Vec2;

/// The preference `s(k, k)` of affinity propagation.
#[derive(Copy, Clone, Debug, PartialEq)]
pub enum Preference {
    /// The median of the similarities (Frey & Dueck's default).
    Median,
    /// This value.
    Value(f64),
}

/// Affinity propagation's parameters.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct ApParams {
    /// Damping `λ` of the messages, in `[0.5, 1)`.
    pub damping: f64,
    /// Most iterations.
    pub max_iterations: u32,
    /// Iterations with unchanged exemplars that count as converged.
    pub convergence_iterations: u32,
    /// `s(k, k)`.
    pub preference: Preference,
    /// Candidate pairs of a large crowd: the Delaunay `ring`-ring of each source point.
    pub ring: u32,
    /// Crowds up to this size use every pair (dense).
    pub dense_up_to: usize,
}

impl Default for ApParams {
    fn default() -> ApParams {
        todo!()
    }
}

/// A partition of the agents into subgroups.
#[derive(Clone, Debug, PartialEq)]
pub struct Subgroups {
    /// `group_of[i]`: agent `i`'s subgroup, `0..count()`.
    pub group_of: Vec<u32>,
    /// The exemplar (agent index) of each subgroup.
    pub exemplars: Vec<u32>,
    /// Iterations run.
    pub iterations: u32,
    /// Whether the exemplars settled before `max_iterations`.
    pub converged: bool,
}

impl Subgroups {
    /// Every agent in one subgroup (subgroups off).
    pub fn single(n: usize) -> Subgroups {
        let _ = n;
        todo!()
    }

    /// Number of subgroups.
    pub fn count(&self) -> usize {
        self.exemplars.len()
    }
}

/// Clusters the source points by affinity propagation on the similarity
/// `−Δdis(s_i, s_j)` of eq. 20 (Manhattan edge weights), `paired_targets[i]` being
/// agent `i`'s target `Ψ(s_i)`. `None` when `cancel` said so.
pub fn subgroups(
    sources: &[Vec2],
    paired_targets: &[Vec2],
    p: &ApParams,
    cancel: Cancel<'_>,
) -> Option<Subgroups> {
    let _ = (sources, paired_targets, p, cancel);
    todo!()
}
