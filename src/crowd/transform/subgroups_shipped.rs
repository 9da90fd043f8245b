//! Tests of the subgroups (`subgroups.rs`, `subgroup_merge.rs`) on shipped
//! formation pairs at 100 to 2,000 agents, and of the paper's eq. 20 for what it
//! is (formation-transform section 3.4).

use super::experiment::locality;
use super::pairing::{pair, PairCost};
use super::subgroups::{subgroups, ApParams, Similarity, Subgroups};
use crate::crowd::assign::Cancel;
use crate::crowd::formation::{FormationLibrary, Placement, SampleParams};
use crate::geom::Vec2;

/// Agent radius of the crowds (m).
const RADIUS_M: f64 = 0.15;

/// `n` agents sampled in the shipped formation `from` and paired (least effort,
/// λ = 0.5) with `n` targets sampled in `to`, both on 0.12 m² per agent (agents
/// 0.3 m apart fill about 65 % of it): `(sources, paired targets)`.
fn shipped_pair(from: &str, to: &str, n: usize, seed: u64) -> (Vec<Vec2>, Vec<Vec2>) {
    let lib = FormationLibrary::shipped();
    let place = Placement {
        centre_m: Vec2::new(8.0, 4.5),
        heading: Vec2::new(1.0, 0.0),
        area_m2: 0.12 * n as f64,
    };
    let sample = SampleParams {
        min_spacing_m: 2.0 * RADIUS_M,
        relax_iterations: 30,
    };
    let get = |name: &str, seed: u64| {
        lib.get(name)
            .unwrap_or_else(|| panic!("no shipped formation {name}"))
            .sample(&place, n, &sample, seed, &|| false)
            .unwrap()
            .unwrap()
    };
    let s = get(from, seed);
    let t = get(to, seed ^ 0x5eed);
    let cost = PairCost::LeastEffort { lambda: 0.5 };
    let target_of = pair(&s, &t, cost, Cancel::NEVER).unwrap();
    let paired = target_of.iter().map(|&j| t[j as usize]).collect();
    (s, paired)
}

/// Agents of each subgroup.
fn sizes(g: &Subgroups) -> Vec<usize> {
    let mut c = vec![0; g.count()];
    for &x in &g.group_of {
        c[x as usize] += 1;
    }
    c
}

/// The default (local) subgroups at one crowd size on the three pairs: converged,
/// locality ≥ 0.8, between `min` and `max` subgroups, each connected in space.
fn local_subgroups_at(n: usize, min: usize, max: usize) {
    for (k, (from, to)) in [
        ("square", "arrow"),
        ("ring", "two_groups"),
        ("line", "heart"),
    ]
    .into_iter()
    .enumerate()
    {
        let (s, t) = shipped_pair(from, to, n, 11 + k as u64);
        let g = subgroups(&s, &t, &ApParams::default(), Cancel::NEVER).unwrap();
        let loc = locality(&s, &g.group_of);
        let sz = sizes(&g);
        eprintln!(
            "{from} -> {to} n={n}: {} subgroups, {} iterations, converged {}, locality {loc:.3}, sizes {}..{}",
            g.count(),
            g.iterations,
            g.converged,
            sz.iter().min().unwrap(),
            sz.iter().max().unwrap()
        );
        assert!(
            g.converged,
            "{from} -> {to} n={n}: not converged after {} iterations",
            g.iterations
        );
        assert!(loc >= 0.8, "{from} -> {to} n={n}: locality {loc:.3}");
        assert!(
            (min..=max).contains(&g.count()),
            "{from} -> {to} n={n}: {} subgroups",
            g.count()
        );
        assert_eq!(g.group_of.len(), n);
        for (x, &e) in g.exemplars.iter().enumerate() {
            assert_eq!(g.group_of[e as usize] as usize, x, "exemplar of {x}");
        }
    }
}

#[test]
fn local_subgroups_at_100_agents() {
    local_subgroups_at(100, 2, 6);
}

#[test]
fn local_subgroups_at_300_agents() {
    local_subgroups_at(300, 4, 11);
}

#[test]
fn local_subgroups_at_1000_agents() {
    local_subgroups_at(1000, 7, 20);
}

#[test]
fn local_subgroups_at_2000_agents() {
    local_subgroups_at(2000, 10, 29);
}

/// Two clusters 20 m apart translated together (their distance does not change)
/// with a band of agents between them scattered: eq. 20 as written gives the far
/// pairs of the two clusters the best similarity (0), so some subgroup takes
/// agents of both; the local similarity never does.
#[test]
fn the_paper_similarity_groups_a_rigid_far_pair() {
    let mut s = Vec::new();
    let mut t = Vec::new();
    let mut side = Vec::new();
    for k in 0..60usize {
        let (x, y) = ((k % 6) as f64 * 0.4, (k / 6) as f64 * 0.4);
        let (dx, which) = match k % 3 {
            0 => (0.0, 0u8),
            1 => (20.0, 1),
            _ => (10.0, 2),
        };
        let p = Vec2::new(x + dx + 0.01 * (k % 7) as f64, y + 0.013 * (k % 5) as f64);
        s.push(p);
        side.push(which);
        t.push(if which == 2 {
            // The middle band turns and spreads to three times its size.
            Vec2::new(10.0 - 3.0 * (p.y - 2.0), 2.0 + 3.0 * (p.x - 11.0))
        } else {
            p + Vec2::new(1.0, 5.0)
        });
    }
    let both = |g: &Subgroups| {
        (0..g.count()).any(|x| {
            let m = |w: u8| (0..s.len()).any(|i| g.group_of[i] as usize == x && side[i] == w);
            m(0) && m(1)
        })
    };
    let paper = ApParams {
        similarity: Similarity::Paper,
        ..ApParams::default()
    };
    let gp = subgroups(&s, &t, &paper, Cancel::NEVER).unwrap();
    assert!(both(&gp), "eq. 20: {gp:?}");
    let gl = subgroups(&s, &t, &ApParams::default(), Cancel::NEVER).unwrap();
    assert!(!both(&gl), "local: {gl:?}");
    assert!(locality(&s, &gl.group_of) > locality(&s, &gp.group_of));
}

/// The default subgroups over ten seeds on each of the three pairs at 100 to 2,000
/// agents (120 crowds; release build, about a minute:
/// `cargo test --release --lib subgroups_over_ten_seeds -- --ignored --nocapture`).
/// Every one converges within `max_iterations`; from 300 agents every one has
/// locality ≥ 0.8. At 100 agents the subgroups (3 to 6 of at least 15 agents)
/// have borders as long as themselves, and locality is printed, not required:
/// cutting the 100-agent line into as many slabs as affinity propagation finds
/// subgroups gives 0.77 to 0.91 itself.
#[test]
#[ignore]
fn subgroups_over_ten_seeds() {
    for n in [100usize, 300, 1000, 2000] {
        let (mut converged, mut local, mut lowest, mut most) = (0, 0, 1.0f64, 0u32);
        for (from, to) in [
            ("square", "arrow"),
            ("ring", "two_groups"),
            ("line", "heart"),
        ] {
            for seed in 1..=10u64 {
                let (s, t) = shipped_pair(from, to, n, seed * 7919);
                let g = subgroups(&s, &t, &ApParams::default(), Cancel::NEVER).unwrap();
                let loc = locality(&s, &g.group_of);
                assert!(
                    g.converged,
                    "{from} -> {to} n={n} seed {seed}: not converged in {} iterations",
                    g.iterations
                );
                assert!(
                    n < 300 || loc >= 0.8,
                    "{from} -> {to} n={n} seed {seed}: locality {loc:.3}"
                );
                converged += 1;
                local += usize::from(loc >= 0.8);
                lowest = lowest.min(loc);
                most = most.max(g.iterations);
            }
        }
        eprintln!(
            "n={n}: converged {converged} of 30, locality >= 0.8 in {local} of 30 (lowest {lowest:.3}), at most {most} iterations"
        );
    }
}
