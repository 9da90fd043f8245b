//! The crowd's deformable triangle mesh (mesh-formation-control section 4.1) and the
//! operations on it, one file each: the mesh and its queries ([`TriMesh`]), goal
//! points on it ([`sample_goals`]), as-rigid-as-possible deformation ([`Arap`]) and
//! mean value coordinates for area controls ([`mean_value_coordinates`]).

mod arap;
mod mvc;
mod trimesh;

pub use arap::{Arap, ArapBuffer, ArapError, Constraint, ANCHOR_WEIGHT, MAX_CONSTRAINT_WEIGHT};
pub use mvc::{
    convex_hull, mean_value_coordinates, point_in_convex_polygon, MvcError, MVC_EDGE_EPS,
    MVC_VERTEX_EPS,
};
pub use trimesh::{
    distance_to_mesh, goal_positions, nearest_vertex, sample_goals, GoalSample, MeshError, TriMesh,
    GOAL_CANDIDATES_PER_SAMPLE, GOAL_LLOYD_ITERATIONS,
};
