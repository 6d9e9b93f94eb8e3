//! The report of `tensegrity equilibrium`: the equilibrium matrix of a pin-jointed structure at
//! its settled state and its four subspaces (`structure::equilibrium`), as a table and as JSON.

use serde::Serialize;
use std::fmt::Write;

/// Nodes listed per mechanism: the ones that move most.
pub const MECHANISM_NODES_LISTED: usize = 5;

/// The equilibrium matrix's counts and subspaces.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct EquilibriumReport {
    pub name: String,
    pub file: String,
    /// Whether the settle criteria were met before the analysis.
    pub settled: bool,
    pub settle_steps: u64,
    /// Rows: three per free node, less the coordinates that supports hold (3 j - h).
    pub rows: usize,
    /// The free nodes that members reach (j).
    pub free_nodes: usize,
    /// The free nodes' coordinates that supports in some directions hold (h).
    pub held_coordinates: usize,
    /// Columns: one per member with a free node (b).
    pub columns: usize,
    pub rank: usize,
    /// s = b - r.
    pub self_stress_states: usize,
    /// m = 3 j - h - r (a free structure's rigid motions among them).
    pub mechanisms: usize,
    pub rank_tolerance: f64,
    /// Largest first: all of them (the dense SVD), or, above its bound, the largest and the
    /// smallest nonzero (the sparse null spaces).
    pub singular_values: Vec<f64>,
    /// Whether `singular_values` are all of them.
    pub all_singular_values: bool,
    /// Each state's tension per member (largest magnitude 1, the cables' sum positive).
    pub self_stress: Vec<Vec<(String, f64)>>,
    /// Each mechanism's unit node displacements (x, y, z per free node, by name).
    pub mechanism_shapes: Vec<Vec<(String, [f64; 3])>>,
    /// The force each support (a node on a fixed body that a member reaches) exerts on the
    /// structure at the settled state \[N\], by node.
    pub reactions_n: Vec<(String, [f64; 3])>,
    /// The linear analysis beside the exact settle, where the file states point loads.
    pub linear: Option<LinearReport>,
    /// Why a file with point loads has no linear analysis (a rigid member, a mechanism).
    pub linear_refused: Option<String>,
    pub wall_s: f64,
}

/// The linear (small-displacement) analysis about the structure settled without its point
/// loads (`structure::linear`), beside the exact settle under them.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct LinearReport {
    /// Whether the reference (the structure without its point loads) met the settle criteria.
    pub reference_settled: bool,
    pub reference_settle_steps: u64,
    /// Per free node: its name, the exact displacement (the settle under the loads less the
    /// reference) and the linear one \[m\].
    pub displacements_m: Vec<(String, [f64; 3], [f64; 3])>,
    /// Per member with a free node: its name, the exact force and the linear one \[N\].
    pub forces_n: Vec<(String, f64, f64)>,
}

impl LinearReport {
    /// The largest node displacement of the exact settle, and the largest distance between
    /// the exact and the linear displacement of a node \[m\].
    pub fn largest_displacements_m(&self) -> (f64, f64) {
        self.displacements_m.iter().fold((0.0_f64, 0.0_f64), |(d, e), (_, exact, linear)| {
            (d.max(norm(*exact)), e.max(norm([0, 1, 2].map(|x| exact[x] - linear[x]))))
        })
    }

    /// The largest member force of the exact settle, and the largest difference between the
    /// exact and the linear force \[N\].
    pub fn largest_forces_n(&self) -> (f64, f64) {
        self.forces_n
            .iter()
            .fold((0.0_f64, 0.0_f64), |(f, e), (_, exact, linear)| (f.max(exact.abs()), e.max((exact - linear).abs())))
    }

    /// The table's lines: the largest differences, then each node and member.
    fn write(&self, out: &mut String) {
        let (d, dd) = self.largest_displacements_m();
        let (f, df) = self.largest_forces_n();
        let _ = writeln!(
            out,
            "   linear analysis about the structure without its point loads (settled: {}, {} steps), beside the exact settle under them:",
            self.reference_settled, self.reference_settle_steps
        );
        let _ = writeln!(
            out,
            "     largest displacement {d:.6e} m, linear off by {dd:.3e} m ({:.3e} of it); largest force {f:.6e} N, linear off by {df:.3e} N ({:.3e} of it)",
            dd / d.max(f64::MIN_POSITIVE),
            df / f.max(f64::MIN_POSITIVE)
        );
        for (node, exact, linear) in &self.displacements_m {
            let _ = writeln!(
                out,
                "     {node:<20} exact {:+.9e} {:+.9e} {:+.9e}  linear {:+.9e} {:+.9e} {:+.9e}",
                exact[0], exact[1], exact[2], linear[0], linear[1], linear[2]
            );
        }
        for (member, exact, linear) in &self.forces_n {
            let _ = writeln!(out, "     {member:<20} exact {exact:+.9e} N  linear {linear:+.9e} N");
        }
    }
}

impl EquilibriumReport {
    /// The table: counts, Maxwell's rule, each self-stress state and each mechanism's most
    /// moving nodes (its localisation).
    pub fn to_table(&self) -> String {
        let mut out = String::new();
        let _ = writeln!(out, "== {} [{}]: equilibrium matrix at the settled state", self.name, self.file);
        let _ = writeln!(out, "   settled: {} ({} steps)", self.settled, self.settle_steps);
        let held = if self.held_coordinates > 0 { " - h" } else { "" };
        let _ = writeln!(
            out,
            "   A: {} rows (3 j{held}, j = {} free nodes, h = {} coordinates held by supports) by {} columns (b members); rank r = {} (singular values below {:e} of the largest are zero)",
            self.rows,
            self.free_nodes,
            self.held_coordinates,
            self.columns,
            self.rank,
            self.rank_tolerance
        );
        let _ = writeln!(
            out,
            "   s = b - r = {} self-stress state(s), m = 3 j{held} - r = {} mechanism(s); Maxwell-Calladine 3 j{held} - b = {} = m - s",
            self.self_stress_states,
            self.mechanisms,
            self.rows as i64 - self.columns as i64
        );
        for (k, state) in self.self_stress.iter().enumerate() {
            let _ = writeln!(out, "   self-stress {}:", k + 1);
            for (member, t) in state {
                let _ = writeln!(out, "     {member:<20} {t:+.9}");
            }
        }
        if !self.reactions_n.is_empty() {
            let _ = writeln!(out, "   reactions at the supports [N]:");
            for (node, r) in &self.reactions_n {
                let _ = writeln!(out, "     {node:<20} {:+.9e} {:+.9e} {:+.9e}", r[0], r[1], r[2]);
            }
        }
        if let Some(linear) = &self.linear {
            linear.write(&mut out);
        }
        if let Some(why) = &self.linear_refused {
            let _ = writeln!(out, "   no linear analysis: {why}");
        }
        if !self.all_singular_values {
            let _ = writeln!(
                out,
                "   sparse analysis (above the dense SVD's bound): singular values largest {:.6e}{}",
                self.singular_values.first().copied().unwrap_or(0.0),
                self.singular_values.get(1).map_or(String::new(), |x| format!(", smallest nonzero {x:.6e}"))
            );
        }
        if self.mechanism_shapes.len() < self.mechanisms {
            let _ = writeln!(
                out,
                "   the {} mechanisms' shapes are not computed (the sparse analysis computes null spaces of at most {})",
                self.mechanisms,
                crate::structure::sparse_null::MAX_NULL
            );
        }
        for (k, shape) in self.mechanism_shapes.iter().enumerate() {
            let mut moving: Vec<&(String, [f64; 3])> = shape.iter().collect();
            moving.sort_by(|a, b| norm(b.1).total_cmp(&norm(a.1)));
            let listed: Vec<String> =
                moving.iter().take(MECHANISM_NODES_LISTED).map(|(n, d)| format!("{n} {:.3}", norm(*d))).collect();
            let _ = writeln!(out, "   mechanism {}: moves most {}", k + 1, listed.join(", "));
        }
        out
    }
}

fn norm(d: [f64; 3]) -> f64 {
    (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt()
}
