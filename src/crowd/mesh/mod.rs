//! The crowd's deformable triangle mesh (mesh-formation-control section 4.1) and the
//! operations on it, one file each: the mesh and its queries ([`TriMesh`]), goal
//! points on it ([`sample_goals`]), as-rigid-as-possible deformation ([`Arap`], with
//! its envelope Cholesky factorisation in `envelope.rs`) and mean value coordinates
//! for area controls ([`mean_value_coordinates`]).

mod arap;
mod around;
mod envelope;
mod goals;
mod mvc;
mod trimesh;

pub use arap::{
    Arap, ArapBuffer, ArapError, Constraint, PointConstraint, ANCHOR_WEIGHT, MAX_CONSTRAINT_WEIGHT,
};
pub use around::{mesh_around, mesh_around_parts, ALPHA_FACTOR, HELPER_OFFSET_FACTOR};
pub use goals::{
    goal_positions, sample_goals, sample_goals_cancellable, GoalSample, GOAL_CANDIDATES_PER_SAMPLE,
    GOAL_LLOYD_ITERATIONS,
};
pub use mvc::{
    convex_hull, mean_value_coordinates, point_in_convex_polygon, MvcError, MVC_EDGE_EPS,
    MVC_VERTEX_EPS,
};
pub use trimesh::{distance_to_mesh, nearest_vertex, MeshError, TriMesh};
