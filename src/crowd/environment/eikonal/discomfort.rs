//! Discomfort `g` of eq. 3 per cell, from the obstacle distance and the crowd
//! density.

use super::error::EikonalError;
use super::grid::{check_len, Grid};
use crate::geom::Vec2;

/// Distance from an obstacle, in metres, beyond which it adds no discomfort
/// ([`DiscomfortParams::default`]).
pub const DEFAULT_OBSTACLE_RANGE_M: f64 = 0.5;
/// Discomfort at an obstacle's boundary ([`DiscomfortParams::default`]).
pub const DEFAULT_OBSTACLE_DISCOMFORT: f64 = 1.0;
/// Discomfort per unit of crowd density, in m² per agent: 0.25 m² makes 4 agents/m²
/// one unit of discomfort ([`DiscomfortParams::default`]).
pub const DEFAULT_DENSITY_DISCOMFORT_M2: f64 = 0.25;

/// How discomfort `g` is built from obstacles and crowd density.
///
/// # Units
/// `obstacle_range_m` in metres; `obstacle` dimensionless; `density_m2` in m² per
/// agent (discomfort per agent/m² of density).
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct DiscomfortParams {
    /// Distance from an obstacle beyond which it adds nothing.
    pub obstacle_range_m: f64,
    /// Discomfort at the obstacle boundary, falling linearly to 0 at the range.
    pub obstacle: f64,
    /// Discomfort per unit of density (agents per m²).
    pub density_m2: f64,
}

impl Default for DiscomfortParams {
    fn default() -> DiscomfortParams {
        DiscomfortParams {
            obstacle_range_m: DEFAULT_OBSTACLE_RANGE_M,
            obstacle: DEFAULT_OBSTACLE_DISCOMFORT,
            density_m2: DEFAULT_DENSITY_DISCOMFORT_M2,
        }
    }
}

/// Builds the discomfort `g` of eq. 3 per cell from the obstacle distance and a
/// density splat of agent positions.
///
/// # Formula
/// `g = g_obs · max(0, 1 − d / d_range) + w_ρ · ρ`, with `d` the distance to the
/// nearest obstacle and `ρ` the crowd density: each agent is splatted bilinearly
/// onto the four cell centres around it and the weights divided by the cell area.
/// mesh-formation-control section 6.2.1 takes the discomfort of "obstacles and other
/// agents" from its reference \[6\] without a formula; this linear falloff and the
/// bilinear splat are ours. An agent counts in its own density.
///
/// # Units
/// `obstacle_distance_m` in metres (0 or negative inside obstacles); density in
/// agents per m²; `g` dimensionless.
///
/// # Errors
/// [`EikonalError::SizeMismatch`]; [`EikonalError::InvalidInput`] for a parameter
/// that is negative or not finite (the range must be positive), or a NaN distance;
/// [`EikonalError::PointNotFinite`] for an agent position. Agents outside the grid
/// are ignored.
pub fn discomfort_into(
    grid: &Grid,
    obstacle_distance_m: &[f64],
    agents: &[Vec2],
    params: DiscomfortParams,
    out: &mut [f64],
) -> Result<(), EikonalError> {
    check_len("obstacle_distance_m", grid, obstacle_distance_m.len())?;
    check_len("out", grid, out.len())?;
    let bad = |what| EikonalError::InvalidInput { what, index: 0 };
    if !(params.obstacle_range_m.is_finite() && params.obstacle_range_m > 0.0) {
        return Err(bad("obstacle_range_m"));
    }
    if !(params.obstacle.is_finite() && params.obstacle >= 0.0) {
        return Err(bad("obstacle"));
    }
    if !(params.density_m2.is_finite() && params.density_m2 >= 0.0) {
        return Err(bad("density_m2"));
    }
    for (i, (&d, g)) in obstacle_distance_m.iter().zip(out.iter_mut()).enumerate() {
        if d.is_nan() {
            return Err(EikonalError::InvalidInput {
                what: "obstacle_distance_m",
                index: i,
            });
        }
        *g = params.obstacle * (1.0 - d / params.obstacle_range_m).clamp(0.0, 1.0);
    }
    for (point, a) in agents.iter().enumerate() {
        if !(a.x.is_finite() && a.y.is_finite()) {
            return Err(EikonalError::PointNotFinite { point });
        }
    }
    if params.density_m2 == 0.0 {
        return Ok(());
    }
    let per_agent = params.density_m2 / (grid.cell_m * grid.cell_m);
    for &a in agents {
        if !grid.contains(a) {
            continue;
        }
        let (cells, tx, ty) = grid.stencil_cells(a);
        let w = [
            (1.0 - tx) * (1.0 - ty),
            tx * (1.0 - ty),
            (1.0 - tx) * ty,
            tx * ty,
        ];
        for k in 0..4 {
            out[cells[k]] += per_agent * w[k];
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn discomfort_from_obstacles_and_density() {
        let grid = Grid::new(4, 4, 0.5, Vec2::zeros()).unwrap();
        let mut dist = vec![10.0; 16];
        dist[0] = 0.0;
        dist[1] = 0.25;
        let mut g = vec![0.0; 16];
        // One agent at the centre of cell (2, 2): all of it lands there.
        discomfort_into(
            &grid,
            &dist,
            &[grid.center(grid.index(2, 2))],
            DiscomfortParams::default(),
            &mut g,
        )
        .unwrap();
        assert!((g[0] - 1.0).abs() < 1e-15);
        assert!((g[1] - 0.5).abs() < 1e-15);
        assert!((g[grid.index(2, 2)] - 0.25 / 0.25).abs() < 1e-12);
        let total: f64 = g.iter().sum::<f64>() - 1.5;
        assert!((total - 1.0).abs() < 1e-12);
        // A splat between centres conserves the agent.
        discomfort_into(
            &grid,
            &[10.0; 16],
            &[Vec2::new(1.1, 0.9)],
            DiscomfortParams::default(),
            &mut g,
        )
        .unwrap();
        assert!((g.iter().sum::<f64>() * 0.25 / 0.25 - 1.0).abs() < 1e-12);
        assert_eq!(
            discomfort_into(
                &grid,
                &dist,
                &[Vec2::new(f64::NAN, 0.0)],
                DiscomfortParams::default(),
                &mut g
            ),
            Err(EikonalError::PointNotFinite { point: 0 })
        );
    }
}
