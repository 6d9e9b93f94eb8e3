//! A structure in the notation of Skelton and de Oliveira (Tensegrity Systems, 2009), used by
//! TsgFEM and MOTES: a node matrix N (3 x n, one column per node, m) and connectivity matrices
//! C_b (bars x n) and C_s (strings x n) whose rows hold one -1 and one 1 (the member runs from
//! the -1 node to the 1 node; the sign does not matter here) and zeros, as CSV files.
//!
//! Made of it: each bar a strut on its own rigid body (a class-1 structure: no node on two
//! bars); nodes on no bar are fixed points (one fixed body "ground"); without such points the
//! first bar's body is held fixed to remove the rigid motion. Each string an elastic
//! tension-only cable whose rest length is the drawn length minus its initial tension over its
//! stiffness. Member properties come from [`MatrixOptions`].

use super::draft::{Draft, DraftBody, DraftCable, DraftStrut};
use super::{ImportError, Imported};
use crate::structure::{distance, Vec3};
use std::path::Path;

#[derive(Clone, Debug)]
pub struct MatrixOptions {
    /// Mass of each bar [kg].
    pub bar_mass_kg: f64,
    /// Radius of each bar [m].
    pub bar_radius_m: f64,
    /// Stiffness of each string [N/m].
    pub string_stiffness_n_per_m: f64,
    /// The least string tension at the drawn state [N]: the drawn structure's self-stress is
    /// scaled to it (each string's rest length set by its share); with `uniform_tension`, or
    /// when the drawing has no self-stress with every string in tension, every string's.
    pub string_tension_n: f64,
    /// Every string at `string_tension_n`, whatever the self-stress.
    pub uniform_tension: bool,
}

impl MatrixOptions {
    /// The command's defaults.
    pub const DEFAULT: MatrixOptions = MatrixOptions {
        bar_mass_kg: 1.0,
        bar_radius_m: 0.01,
        string_stiffness_n_per_m: 1000.0,
        string_tension_n: super::DEFAULT_LEAST_TENSION_N,
        uniform_tension: false,
    };

    /// Every option in its range, or the first that is not, named by its flag.
    pub fn validate(&self) -> Result<(), String> {
        let positive = [
            ("--bar-mass", self.bar_mass_kg),
            ("--bar-radius", self.bar_radius_m),
            ("--string-stiffness", self.string_stiffness_n_per_m),
        ];
        if let Some((flag, x)) = positive.iter().find(|(_, x)| !(*x > 0.0 && x.is_finite())) {
            return Err(format!("{flag} must be a finite number > 0, got {x}"));
        }
        if !(self.string_tension_n >= 0.0 && self.string_tension_n.is_finite()) {
            return Err(format!("--string-tension must be a finite number >= 0, got {}", self.string_tension_n));
        }
        Ok(())
    }
}

/// A row of a matrix file: its line in the file (from 1) and its values.
type Row = (usize, Vec<f64>);

/// A CSV matrix of numbers: rows of comma- (or whitespace-) separated values; `#` comments
/// and blank lines skipped (each row keeps its line number).
fn read_matrix(path: &Path) -> Result<Vec<Row>, ImportError> {
    let file = path.display().to_string();
    let text = super::read_text(path)?;
    let mut rows = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let line = line.split('#').next().unwrap_or("").trim();
        if line.is_empty() {
            continue;
        }
        let mut row = Vec::new();
        let mut col = 1;
        for field in line.split(|c: char| c == ',' || c == ';' || c.is_whitespace()) {
            if field.is_empty() {
                continue;
            }
            let x: f64 = field.parse().ok().filter(|x: &f64| x.is_finite()).ok_or_else(|| ImportError {
                file: file.clone(),
                line: i + 1,
                col,
                message: format!("'{field}' is not a finite number"),
            })?;
            row.push(x);
            col += 1;
        }
        if let Some(first) = rows.first().map(|r: &(usize, Vec<f64>)| r.1.len()) {
            if row.len() != first {
                return Err(ImportError {
                    file,
                    line: i + 1,
                    col: 1,
                    message: format!("{} values where the first row has {first}", row.len()),
                });
            }
        }
        rows.push((i + 1, row));
    }
    if rows.is_empty() {
        return Err(ImportError { file, line: 0, col: 0, message: "the matrix is empty".into() });
    }
    Ok(rows)
}

/// The members of a connectivity matrix: (from node, to node, line) per row; value number
/// `k` of a row is column `k` (node `k`).
fn members(path: &Path, c: &[Row], n: usize) -> Result<Vec<(usize, usize, usize)>, ImportError> {
    let file = path.display().to_string();
    let e = |line: usize, message: String| ImportError { file: file.clone(), line, col: 1, message };
    let mut out = Vec::new();
    for (i, row) in c {
        let i = *i;
        if row.len() != n {
            return Err(e(i, format!("{} columns, but N has {n} nodes", row.len())));
        }
        let from: Vec<usize> = (0..n).filter(|&k| row[k] == -1.0).collect();
        let to: Vec<usize> = (0..n).filter(|&k| row[k] == 1.0).collect();
        if from.len() != 1 || to.len() != 1 || row.iter().any(|x| ![-1.0, 0.0, 1.0].contains(x)) {
            return Err(e(i, "a member's row holds one -1, one 1 and zeros".into()));
        }
        out.push((from[0], to[0], i));
    }
    Ok(out)
}

/// A member as read from a connectivity row: its two nodes (from 0) and the row's line.
type Member = (usize, usize, usize);

/// Imports N, C_b and C_s.
pub fn import(n_path: &Path, cb_path: &Path, cs_path: &Path, o: &MatrixOptions) -> Result<Imported, ImportError> {
    let n = read_matrix(n_path)?;
    if n.len() != 3 {
        return Err(ImportError {
            file: n_path.display().to_string(),
            line: 0,
            col: 0,
            message: format!("N must have 3 rows (x, y, z of each node), got {}", n.len()),
        });
    }
    let count = n[0].1.len();
    let nodes: Vec<Vec3> = (0..count).map(|k| [n[0].1[k], n[1].1[k], n[2].1[k]]).collect();
    let bars = members(cb_path, &read_matrix(cb_path)?, count)?;
    let strings = members(cs_path, &read_matrix(cs_path)?, count)?;
    let on_bar = bar_of_each_node(cb_path, &bars, count)?;
    let ground: Vec<usize> = (0..count).filter(|&k| on_bar[k].is_none()).collect();
    let mut draft = Draft {
        name: format!(
            "{} (from N, C_b, C_s)",
            n_path.file_stem().map(|s| s.to_string_lossy().to_string()).unwrap_or_default()
        ),
        ..Default::default()
    };
    if !ground.is_empty() {
        draft.bodies.push(DraftBody {
            name: "ground".into(),
            fixed: true,
            mass_kg: 0.0,
            inertia_kg_m2: None,
            nodes: ground.iter().map(|&k| (node_name(k), nodes[k])).collect(),
        });
    }
    add_bars(&mut draft, &nodes, &bars, ground.is_empty(), o);
    add_strings(&mut draft, &nodes, &strings, cs_path, o)?;
    let chosen = prestress(&mut draft, o).map_err(|message| ImportError::whole(cs_path, message))?;
    draft.description = description([n_path, cb_path, cs_path], o, ground.len()) + "\n" + &chosen;
    let toml = draft.to_toml().map_err(|message| ImportError::whole(n_path, message))?;
    Ok(Imported { toml, skipped: Vec::new(), chosen: vec![chosen] })
}

/// Node k (from 0) is n<k+1>, column k+1 of N.
fn node_name(k: usize) -> String {
    format!("n{}", k + 1)
}

/// The bar each node is on, if any; a node on two bars is an error (class 1 only).
fn bar_of_each_node(cb_path: &Path, bars: &[Member], count: usize) -> Result<Vec<Option<usize>>, ImportError> {
    let mut on_bar: Vec<Option<usize>> = vec![None; count];
    for (i, &(a, b, line)) in bars.iter().enumerate() {
        for k in [a, b] {
            if let Some(j) = on_bar[k] {
                return Err(ImportError {
                    file: cb_path.display().to_string(),
                    line,
                    col: 1,
                    message: format!(
                        "node {} is on bars {} and {}: only class-1 structures (no node on two bars)",
                        k + 1,
                        j + 1,
                        i + 1
                    ),
                });
            }
            on_bar[k] = Some(i);
        }
    }
    Ok(on_bar)
}

/// Each bar a strut on its own body (a uniform cylinder's inertia about its centre, taken
/// as the same about every axis); the first held fixed when `fix_first` (no ground).
fn add_bars(draft: &mut Draft, nodes: &[Vec3], bars: &[Member], fix_first: bool, o: &MatrixOptions) {
    for (i, &(a, b, _)) in bars.iter().enumerate() {
        let l = distance(nodes[a], nodes[b]);
        let inertia = o.bar_mass_kg * (3.0 * o.bar_radius_m * o.bar_radius_m + l * l) / 12.0;
        draft.bodies.push(DraftBody {
            name: format!("bar{}", i + 1),
            fixed: fix_first && i == 0,
            mass_kg: o.bar_mass_kg,
            inertia_kg_m2: Some([inertia; 3]),
            nodes: vec![(node_name(a), nodes[a]), (node_name(b), nodes[b])],
        });
        draft.struts.push(DraftStrut {
            name: format!("bar{}", i + 1),
            a: node_name(a),
            b: node_name(b),
            radius_m: o.bar_radius_m,
        });
    }
}

/// Each string an elastic tension-only cable whose rest length is the drawn length less the
/// tension over the stiffness; no rest length left is an error at the string's row.
fn add_strings(
    draft: &mut Draft,
    nodes: &[Vec3],
    strings: &[Member],
    cs_path: &Path,
    o: &MatrixOptions,
) -> Result<(), ImportError> {
    for (i, &(a, b, line)) in strings.iter().enumerate() {
        let l = distance(nodes[a], nodes[b]);
        let rest = l - o.string_tension_n / o.string_stiffness_n_per_m;
        if !(rest > 0.0) {
            return Err(ImportError {
                file: cs_path.display().to_string(),
                line,
                col: 1,
                message: format!(
                    "string {}: tension {} N at {} N/m leaves no rest length (drawn {l} m)",
                    i + 1,
                    o.string_tension_n,
                    o.string_stiffness_n_per_m
                ),
            });
        }
        draft.cables.push(DraftCable {
            name: format!("string{}", i + 1),
            a: node_name(a),
            b: node_name(b),
            stiffness_n_per_m: Some(o.string_stiffness_n_per_m),
            length_m: rest,
        });
    }
    Ok(())
}

/// The strings' tensions at the drawn state: the drawn structure's self-stress, its least
/// string tension `--string-tension`, unless `--uniform-tension` or the drawing has none with
/// every string in tension (then every string at it, as [`add_strings`] set them); what was
/// chosen, in a sentence.
fn prestress(draft: &mut Draft, o: &MatrixOptions) -> Result<String, String> {
    if o.uniform_tension {
        return Ok(format!(
            "prestress: every string at {} N at the drawn state (--uniform-tension).",
            o.string_tension_n
        ));
    }
    Ok(match super::self_stress::prestress(draft, o.string_tension_n)? {
        Some(c) => format!("{}.", c.sentence),
        None => format!(
            "prestress: the drawn structure has no self-stress with every string in tension, so every string is at {} N \
             at the drawn state, which is then no equilibrium: the structure moves, and the run fails if it loses its prestress.",
            o.string_tension_n
        ),
    })
}

/// What the scenario file says of where it came from and what was chosen.
fn description([n_path, cb_path, cs_path]: [&Path; 3], o: &MatrixOptions, grounded: usize) -> String {
    format!(
        "Imported from N = {}, C_b = {}, C_s = {} (Skelton and de Oliveira's notation) by `tensegrity import matrices`.\n\
         Node k is n<k> (column k of N); bar i is strut bar<i> on its own body of {} kg, radius {} m; string i is the elastic tension-only cable string<i> of {} N/m (rest length = drawn - tension / stiffness).\n{}",
        n_path.display(),
        cb_path.display(),
        cs_path.display(),
        o.bar_mass_kg,
        o.bar_radius_m,
        o.string_stiffness_n_per_m,
        if grounded == 0 { "No node is off the bars: bar1 is held fixed to remove the rigid motion.".to_string() } else { format!("{grounded} node(s) on no bar are fixed points (body 'ground').") }
    )
}
