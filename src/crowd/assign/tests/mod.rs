//! Tests of the assignment solver, end to end: its answers against brute force, the
//! dense strategy and the `pathfinding` crate's Kuhn–Munkres (`optimality`), the
//! geometric fast path against the matrix (`points`), and what it does with every kind
//! of input (`inputs`); the assigner on the hard layouts (`layouts`); cancelled solves
//! (`cancel`).

mod cancel;
mod inputs;
mod layouts;
mod optimality;
mod points;
mod support;
