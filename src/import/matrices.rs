//! A structure in the notation of Skelton and de Oliveira (Tensegrity Systems, 2009), used by
//! TsgFEM and MOTES: a node matrix N (3 x n, one column per node, m) and connectivity matrices
//! C_b (bars x n) and C_s (strings x n) whose rows hold one -1 and one 1 (the member runs from
//! the -1 node to the 1 node; the sign does not matter here) and zeros, as CSV files.
//!
//! Made of it: each bar a strut on its own rigid body (a class-1 structure: no node on two
//! bars); nodes on no bar are fixed points (one fixed body "ground"); without such points the
//! first bar's body is held fixed to remove the rigid motion. Each string an elastic
//! tension-only cable whose rest length is the drawn length minus its initial tension over its
//! stiffness. Member properties come from [`MatrixOptions`] (the command's, one value for every
//! bar or string) or [`MemberProperties`] (one value per member, with springs, pins and
//! quantities: the Python package's `from_matrices`, through [`from_arrays`]).

use super::draft::{Draft, DraftBody, DraftCable, DraftError, DraftJoint, DraftStrut};
use super::{ImportError, Imported};
use crate::structure::{distance, Vec3};
use std::path::Path;

#[derive(Clone, Debug)]
pub struct MatrixOptions {
    /// Mass of each bar \[kg\].
    pub bar_mass_kg: f64,
    /// Radius of each bar \[m\].
    pub bar_radius_m: f64,
    /// Stiffness of each string [N/m].
    pub string_stiffness_n_per_m: f64,
    /// The least string tension at the drawn state \[N\]: the drawn structure's self-stress is
    /// scaled to it (each string's rest length set by its share); with `uniform_tension`, or
    /// when the drawing has no self-stress with every string in tension, every string's.
    pub string_tension_n: f64,
    /// Every string at `string_tension_n`, whatever the self-stress.
    pub uniform_tension: bool,
    /// A clustering matrix S as CSV ([`MemberProperties::clusters`]), if any.
    pub clusters: Option<std::path::PathBuf>,
}

impl MatrixOptions {
    /// The command's defaults.
    pub const DEFAULT: MatrixOptions = MatrixOptions {
        bar_mass_kg: 1.0,
        bar_radius_m: 0.01,
        string_stiffness_n_per_m: 1000.0,
        string_tension_n: super::DEFAULT_LEAST_TENSION_N,
        uniform_tension: false,
        clusters: None,
    };

    /// Every option in its range, or the first that is not, named by its flag.
    pub fn validate(&self) -> Result<(), PropertyError> {
        let positive = [
            ("--bar-mass", self.bar_mass_kg),
            ("--bar-radius", self.bar_radius_m),
            ("--string-stiffness", self.string_stiffness_n_per_m),
        ];
        if let Some(&(flag, value)) = positive.iter().find(|(_, x)| !(*x > 0.0 && x.is_finite())) {
            return Err(PropertyError::Range { at: flag.to_string(), range: "> 0", value });
        }
        if !(self.string_tension_n >= 0.0 && self.string_tension_n.is_finite()) {
            let value = self.string_tension_n;
            return Err(PropertyError::Range { at: "--string-tension".into(), range: ">= 0", value });
        }
        Ok(())
    }

    /// These options for each of `bars` bars and `strings` strings.
    pub fn per_member(&self, bars: usize, strings: usize) -> MemberProperties {
        MemberProperties {
            bar_mass_kg: vec![self.bar_mass_kg; bars],
            bar_radius_m: vec![self.bar_radius_m; bars],
            string_stiffness_n_per_m: vec![self.string_stiffness_n_per_m; strings],
            string_rest: StringRest::TensionN(vec![self.string_tension_n; strings]),
            tension_only: vec![true; strings],
            pins: Vec::new(),
            quantities: Vec::new(),
            clusters: Vec::new(),
            prestress: if self.uniform_tension {
                DrawnTension::AsGiven
            } else {
                DrawnTension::SelfStress { least_n: self.string_tension_n }
            },
        }
    }
}

/// Each string's rest length: from its tension at its drawn length \[N\] (rest = drawn -
/// tension / stiffness), or given \[m\].
#[derive(Clone, Debug)]
pub enum StringRest {
    TensionN(Vec<f64>),
    LengthM(Vec<f64>),
}

/// One value per member, in the order of the rows of C_b (bars) and C_s (strings).
#[derive(Clone, Debug)]
pub struct MemberProperties {
    /// Mass \[kg\] of each bar.
    pub bar_mass_kg: Vec<f64>,
    /// Radius \[m\] of each bar.
    pub bar_radius_m: Vec<f64>,
    /// Stiffness [N/m] of each string.
    pub string_stiffness_n_per_m: Vec<f64>,
    pub string_rest: StringRest,
    /// Whether each string is a tension-only cable (true) or a linear spring that pushes as
    /// well as pulls (false; a rest length of zero allowed: a zero-free-length spring).
    pub tension_only: Vec<bool>,
    /// Bar nodes pinned to the fixed body "ground" (node name `n<k>`, the axis of a revolute
    /// joint, or None for a spherical joint), each joint named `pin_n<k>`.
    pub pins: Vec<(String, Option<Vec3>)>,
    /// `[[quantities]]` of the scenario: (name, expression of the state).
    pub quantities: Vec<(String, String)>,
    /// How the strings' tensions at the drawn state are chosen.
    pub prestress: DrawnTension,
    /// The clustering matrix S as CTSFEM writes it (empty: none): one row per clustered cable,
    /// one column per string, 1 where the string is a segment of that cable and 0 elsewhere;
    /// a row's strings make one path (or a ring), no string is in two rows.
    pub clusters: Vec<Vec<f64>>,
}

/// How the strings' tensions at the drawn state are chosen.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum DrawnTension {
    /// The drawn structure's own self-stress, scaled so that its least string tension is
    /// `least_n` \[N\] (each string's rest length then follows from its stiffness).
    SelfStress { least_n: f64 },
    /// Each string's tension or rest length as [`MemberProperties::string_rest`] gives it.
    AsGiven,
}

/// An import option or member property out of its range.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum PropertyError {
    /// A list of per-member values of the wrong length.
    #[error("{name} has {got} values: expected {want} (one per {what}) or one number")]
    Count { name: &'static str, got: usize, want: usize, what: &'static str },
    /// A value out of its range (`at`: the flag or argument, with the member's index).
    #[error("{at} must be a finite number {range}, got {value}")]
    Range { at: String, range: &'static str, value: f64 },
}

impl MemberProperties {
    /// One value per member, each in its range: errors name the Python argument (and the
    /// member's index from 0 when there are several).
    pub fn validate(&self, bars: usize, strings: usize) -> Result<(), PropertyError> {
        let (rest_name, rest) = match &self.string_rest {
            StringRest::TensionN(t) => ("string_tension_n", t),
            StringRest::LengthM(l) => ("string_rest_length_m", l),
        };
        let counts = [
            ("bar_mass_kg", self.bar_mass_kg.len(), bars, "bar"),
            ("bar_radius_m", self.bar_radius_m.len(), bars, "bar"),
            ("string_stiffness_n_per_m", self.string_stiffness_n_per_m.len(), strings, "string"),
            (rest_name, rest.len(), strings, "string"),
            ("tension_only", self.tension_only.len(), strings, "string"),
        ];
        if let Some(&(name, got, want, what)) = counts.iter().find(|(_, got, want, _)| got != want) {
            return Err(PropertyError::Count { name, got, want, what });
        }
        let ranges: [(&str, &[f64], bool); 4] = [
            ("bar_mass_kg", &self.bar_mass_kg, true),
            ("bar_radius_m", &self.bar_radius_m, true),
            ("string_stiffness_n_per_m", &self.string_stiffness_n_per_m, true),
            (rest_name, rest, false),
        ];
        for (name, values, positive) in ranges {
            let bad = |x: f64| !x.is_finite() || x < 0.0 || (positive && x == 0.0);
            if let Some((i, x)) = values.iter().enumerate().find(|(_, x)| bad(**x)) {
                let at = if values.len() > 1 { format!("{name}[{i}]") } else { name.to_string() };
                let range = if positive { "> 0" } else { ">= 0" };
                return Err(PropertyError::Range { at, range, value: *x });
            }
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

/// Imports N, C_b and C_s from files.
pub fn import(n_path: &Path, cb_path: &Path, cs_path: &Path, o: &MatrixOptions) -> Result<Imported, ImportError> {
    let n = read_matrix(n_path)?;
    let nodes = node_columns(n_path, &n)?;
    let bars = members(cb_path, &read_matrix(cb_path)?, nodes.len())?;
    let strings = members(cs_path, &read_matrix(cs_path)?, nodes.len())?;
    let mut p = o.per_member(bars.len(), strings.len());
    let s_path = o.clusters.as_deref().unwrap_or(Path::new("S"));
    if let Some(s) = &o.clusters {
        p.clusters = read_matrix(s)?.into_iter().map(|(_, row)| row).collect();
    }
    let (mut draft, grounded, chosen) = build([n_path, cb_path, cs_path, s_path], &nodes, &bars, &strings, &p)?;
    draft.name = format!(
        "{} (from N, C_b, C_s)",
        n_path.file_stem().map(|s| s.to_string_lossy().to_string()).unwrap_or_default()
    );
    draft.description = description(
        &format!("N = {}, C_b = {}, C_s = {}", n_path.display(), cb_path.display(), cs_path.display()),
        "`tensegrity import matrices`",
        &p,
        grounded,
    ) + "\n"
        + &chosen;
    let toml = draft.to_toml().map_err(|e| ImportError::whole(n_path, e.to_string()))?;
    Ok(Imported { toml, skipped: Vec::new(), chosen: vec![chosen] })
}

/// Builds the scenario `name` from N (3 rows of n values), C_b and C_s given as rows of numbers
/// (numpy arrays): errors at `N`, `Cb` or `Cs`, the row as its line counted from 1 (an error
/// of the properties or the pins at no file: "" or `pins`).
pub fn from_arrays(
    name: &str,
    n: &[Vec<f64>],
    cb: &[Vec<f64>],
    cs: &[Vec<f64>],
    p: &MemberProperties,
) -> Result<Imported, ImportError> {
    let paths = [Path::new("N"), Path::new("Cb"), Path::new("Cs"), Path::new("clusters")];
    let rows = |m: &[Vec<f64>]| -> Vec<Row> { m.iter().enumerate().map(|(i, r)| (i + 1, r.clone())).collect() };
    let n_rows = rows(n);
    if let Some((line, r)) = n_rows.iter().find(|(_, r)| r.len() != n_rows[0].1.len()) {
        let message = format!("{} values where the first row has {}", r.len(), n_rows[0].1.len());
        return Err(ImportError { file: "N".into(), line: *line, col: 1, message });
    }
    let nodes = node_columns(paths[0], &n_rows)?;
    let bars = members(paths[1], &rows(cb), nodes.len())?;
    let strings = members(paths[2], &rows(cs), nodes.len())?;
    p.validate(bars.len(), strings.len()).map_err(|e| ImportError::whole(Path::new(""), e.to_string()))?;
    let (mut draft, grounded, chosen) = build(paths, &nodes, &bars, &strings, p)?;
    draft.name = name.to_string();
    draft.description =
        description("numpy arrays N, C_b, C_s", "tensegrity_testbed.from_matrices", p, grounded) + "\n" + &chosen;
    let toml = draft.to_toml().map_err(|e| ImportError::whole(Path::new(""), e.to_string()))?;
    Ok(Imported { toml, skipped: Vec::new(), chosen: vec![chosen] })
}

/// The nodes, one per column of N's three rows (x, y, z).
fn node_columns(n_path: &Path, n: &[Row]) -> Result<Vec<Vec3>, ImportError> {
    if n.len() != 3 {
        return Err(ImportError {
            file: n_path.display().to_string(),
            line: 0,
            col: 0,
            message: format!("N must have 3 rows (x, y, z of each node), got {}", n.len()),
        });
    }
    Ok((0..n[0].1.len()).map(|k| [n[0].1[k], n[1].1[k], n[2].1[k]]).collect())
}

/// The structure: a fixed body "ground" with the nodes on no bar (and a node `ground_n<k>` at
/// each pin whose ground has none), the bars, the pins, the strings and the quantities; and
/// the number of nodes on no bar.
fn build(
    [_, cb_path, cs_path, s_path]: [&Path; 4],
    nodes: &[Vec3],
    bars: &[Member],
    strings: &[Member],
    p: &MemberProperties,
) -> Result<(Draft, usize, String), ImportError> {
    let count = nodes.len();
    let on_bar = bar_of_each_node(cb_path, bars, count)?;
    let ground: Vec<usize> = (0..count).filter(|&k| on_bar[k].is_none()).collect();
    let mut draft = Draft::default();
    let mut ground_nodes: Vec<(String, Vec3)> = ground.iter().map(|&k| (node_name(k), nodes[k])).collect();
    let pins = pins(&p.pins, &on_bar)?;
    if ground_nodes.is_empty() {
        ground_nodes.extend(pins.iter().take(1).map(|&(k, _)| (format!("ground_{}", node_name(k)), nodes[k])));
    }
    if !ground_nodes.is_empty() {
        draft.bodies.push(DraftBody {
            name: "ground".into(),
            fixed: true,
            mass_kg: 0.0,
            inertia_kg_m2: None,
            nodes: ground_nodes,
        });
    }
    let fix_first = draft.bodies.is_empty();
    add_bars(&mut draft, nodes, bars, fix_first, p);
    for &(k, axis) in &pins {
        draft.joints.push(DraftJoint {
            name: format!("pin_{}", node_name(k)),
            parent: "ground".into(),
            child: format!("bar{}", on_bar[k].expect("pins are on bars") + 1),
            at: node_name(k),
            axis,
        });
    }
    add_strings(&mut draft, nodes, strings, cs_path, p)?;
    let rows: Vec<Row> = p.clusters.iter().enumerate().map(|(i, r)| (i + 1, r.clone())).collect();
    cluster_strings(&mut draft, &clusters_of(s_path, &rows, strings.len())?)
        .map_err(|(line, message)| ImportError { file: s_path.display().to_string(), line, col: 1, message })?;
    let chosen = prestress(&mut draft, p).map_err(|e| ImportError::whole(cs_path, e.to_string()))?;
    draft.quantities = p.quantities.clone();
    Ok((draft, ground.len(), chosen))
}

/// Each pin's node (from 0) and axis: a node of N on a bar, pinned once, its axis finite and
/// not zero.
fn pins(pins: &[(String, Option<Vec3>)], on_bar: &[Option<usize>]) -> Result<Vec<(usize, Option<Vec3>)>, ImportError> {
    let e = |message: String| ImportError::whole(Path::new("pins"), message);
    let mut out: Vec<(usize, Option<Vec3>)> = Vec::new();
    for (name, axis) in pins {
        let k = (0..on_bar.len()).find(|&k| node_name(k) == *name).ok_or_else(|| {
            e(format!("no node '{name}' (the nodes are n1 to n{}, one per column of N)", on_bar.len()))
        })?;
        if on_bar[k].is_none() {
            return Err(e(format!(
                "node '{name}' is on no bar (nodes on no bar are fixed already; a pin joins a bar to them)"
            )));
        }
        if out.iter().any(|(j, _)| *j == k) {
            return Err(e(format!("node '{name}' is pinned twice")));
        }
        if let Some(a) = (*axis).filter(|a| !a.iter().all(|x| x.is_finite()) || a.iter().all(|x| *x == 0.0)) {
            return Err(e(format!("the axis of the pin at '{name}' is {a:?}: three finite numbers, not all zero")));
        }
        out.push((k, *axis));
    }
    Ok(out)
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

/// Each bar a strut on its own body, its inertia the scenario file's default for a body that
/// states none (m l^2 / 12 about every axis: a thin rod's about its middle), so that the bar
/// made from matrices and the bar written in TOML have the same physics; the first held fixed
/// when `fix_first` (nothing else fixed).
fn add_bars(draft: &mut Draft, nodes: &[Vec3], bars: &[Member], fix_first: bool, p: &MemberProperties) {
    for (i, &(a, b, _)) in bars.iter().enumerate() {
        let (m, r) = (p.bar_mass_kg[i], p.bar_radius_m[i]);
        draft.bodies.push(DraftBody {
            name: format!("bar{}", i + 1),
            fixed: fix_first && i == 0,
            mass_kg: m,
            inertia_kg_m2: None,
            nodes: vec![(node_name(a), nodes[a]), (node_name(b), nodes[b])],
        });
        draft.struts.push(DraftStrut { name: format!("bar{}", i + 1), a: node_name(a), b: node_name(b), radius_m: r });
    }
}

/// Each string an elastic tension-only cable (or a spring) whose rest length is given or the
/// drawn length less the tension over the stiffness; no rest length left for a cable (a
/// negative one for a spring) is an error at the string's row.
fn add_strings(
    draft: &mut Draft,
    nodes: &[Vec3],
    strings: &[Member],
    cs_path: &Path,
    p: &MemberProperties,
) -> Result<(), ImportError> {
    for (i, &(a, b, line)) in strings.iter().enumerate() {
        let (k, tension_only) = (p.string_stiffness_n_per_m[i], p.tension_only[i]);
        let l = distance(nodes[a], nodes[b]);
        let (rest, given) = match &p.string_rest {
            StringRest::TensionN(t) => (l - t[i] / k, format!("tension {} N at {k} N/m", t[i])),
            StringRest::LengthM(r) => (r[i], format!("rest length {} m", r[i])),
        };
        let name = format!("string{}", i + 1);
        if !(rest > 0.0 || (!tension_only && rest >= 0.0)) {
            let what = if tension_only {
                "no rest length (a tension-only cable needs one > 0)"
            } else {
                "a negative rest length"
            };
            return Err(ImportError {
                file: cs_path.display().to_string(),
                line,
                col: 1,
                message: format!("{name}: {given} leaves {what} (drawn {l} m)"),
            });
        }
        draft.cables.push(DraftCable {
            through: Vec::new(),
            name,
            a: node_name(a),
            b: node_name(b),
            stiffness_n_per_m: Some(k),
            length_m: rest,
            tension_only,
        });
    }
    Ok(())
}

/// The clustered cables of S's rows: each row's strings (from 0), every entry 0 or 1, one
/// column per string, no string in two rows, no row empty.
fn clusters_of(path: &Path, rows: &[Row], strings: usize) -> Result<Vec<Vec<usize>>, ImportError> {
    let at = |line: usize, message: String| ImportError { file: path.display().to_string(), line, col: 1, message };
    let mut owner: Vec<Option<usize>> = vec![None; strings];
    let mut out = Vec::new();
    for (r, (line, row)) in rows.iter().enumerate() {
        if row.len() != strings {
            return Err(at(*line, format!("a row of S has one column per string: {} for {strings}", row.len())));
        }
        if let Some(x) = row.iter().find(|x| **x != 0.0 && **x != 1.0) {
            return Err(at(*line, format!("S holds 0 or 1 (a string in the cable or not), got {x}")));
        }
        let members: Vec<usize> = (0..strings).filter(|&j| row[j] == 1.0).collect();
        if members.is_empty() {
            return Err(at(*line, "a row of S names no string".into()));
        }
        for &j in &members {
            if let Some(other) = owner[j].replace(r) {
                let message = format!(
                    "string{} is in clustered cables {} and {}: rows of S must not overlap",
                    j + 1,
                    other + 1,
                    r + 1
                );
                return Err(at(*line, message));
            }
        }
        out.push(members);
    }
    Ok(out)
}

/// Replaces each cluster's strings by one clustered cable `cluster<r>` through their nodes
/// in path order: its stiffness theirs in series (the same material: 1 / sum 1 / k) and its
/// rest length the sum of theirs (the self-stress, if chosen, sets it again). An error (row
/// from 1, message) where the strings make no single path or one is a spring.
fn cluster_strings(draft: &mut Draft, clusters: &[Vec<usize>]) -> Result<(), (usize, String)> {
    let mut clustered = Vec::new();
    for (r, members) in clusters.iter().enumerate() {
        let strings: Vec<&DraftCable> = members.iter().map(|&j| &draft.cables[j]).collect();
        if let Some(s) = strings.iter().find(|s| !s.tension_only) {
            return Err((r + 1, format!("{} is a spring: only tension-only strings make a clustered cable", s.name)));
        }
        let path = chain(&strings).ok_or_else(|| {
            (r + 1, "the row's strings make no single path (a chain or a ring of segments)".to_string())
        })?;
        let compliance: f64 = strings.iter().map(|s| 1.0 / s.stiffness_n_per_m.unwrap_or(f64::INFINITY)).sum();
        clustered.push(DraftCable {
            name: format!("cluster{}", r + 1),
            a: path[0].clone(),
            through: path[1..path.len() - 1].to_vec(),
            b: path[path.len() - 1].clone(),
            stiffness_n_per_m: Some(1.0 / compliance),
            length_m: strings.iter().map(|s| s.length_m).sum(),
            tension_only: true,
        });
    }
    let gone: Vec<usize> = clusters.iter().flatten().copied().collect();
    let kept = std::mem::take(&mut draft.cables).into_iter().enumerate().filter(|(j, _)| !gone.contains(j));
    draft.cables = kept.map(|(_, c)| c).chain(clustered).collect();
    Ok(())
}

/// The nodes of `segments` (two-node strings) in path order, None unless they make one chain
/// (two ends) or one ring (its first node again at its end).
fn chain(segments: &[&DraftCable]) -> Option<Vec<String>> {
    let degree = |n: &str| segments.iter().filter(|s| s.a == n || s.b == n).count();
    let ends: Vec<&str> =
        segments.iter().flat_map(|s| [s.a.as_str(), s.b.as_str()]).filter(|n| degree(n) == 1).collect();
    let start = match ends.len() {
        0 => segments.first()?.a.clone(),
        2 => ends[0].to_string(),
        _ => return None,
    };
    let mut used = vec![false; segments.len()];
    let mut path = vec![start];
    while let Some(k) = (0..segments.len()).find(|&k| {
        let last = path.last().expect("the start");
        !used[k] && (&segments[k].a == last || &segments[k].b == last)
    }) {
        used[k] = true;
        let last = path.last().expect("the start").clone();
        path.push(if segments[k].a == last { segments[k].b.clone() } else { segments[k].a.clone() });
    }
    used.iter().all(|u| *u).then_some(path)
}

/// `v` as the description says it: the value when every member has it, else its range.
fn said(v: &[f64]) -> String {
    let (lo, hi) = v.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), x| (lo.min(*x), hi.max(*x)));
    if v.is_empty() || lo == hi {
        v.first().map_or("-".into(), |x| x.to_string())
    } else {
        format!("{lo} to {hi} (one per member)")
    }
}

/// The strings' tensions at the drawn state: the drawn structure's self-stress with its least
/// string tension `least_n` ([`DrawnTension::SelfStress`]), unless the strings are as given or
/// the drawing has no self-stress with every string in tension (then as [`add_strings`] set
/// them); what was chosen, in a sentence.
fn prestress(draft: &mut Draft, p: &MemberProperties) -> Result<String, DraftError> {
    let least_n = match p.prestress {
        DrawnTension::AsGiven => {
            return Ok("prestress: every string's tension or rest length as given (not the drawn self-stress).".into())
        }
        DrawnTension::SelfStress { least_n } => least_n,
    };
    Ok(match super::self_stress::prestress(draft, least_n)? {
        Some(c) => format!("{}.", c.sentence),
        None => format!(
            "prestress: the drawn structure has no self-stress with every string in tension, so every string is at {} N \
             at the drawn state, which is then no equilibrium: the structure moves, and the run fails if it loses its prestress.",
            least_n
        ),
    })
}

/// What the scenario file says of where it came from and what was chosen.
fn description(source: &str, by: &str, p: &MemberProperties, grounded: usize) -> String {
    let rest = match &p.string_rest {
        StringRest::TensionN(t) => {
            format!("at {} N when drawn (rest length = drawn - tension / stiffness)", said(t))
        }
        StringRest::LengthM(l) => format!("of rest length {} m", said(l)),
    };
    let kind = match (p.tension_only.iter().all(|t| *t), p.tension_only.iter().any(|t| *t)) {
        (true, _) => "elastic tension-only cable",
        (false, false) => "linear spring (pushes as well as pulls)",
        (false, true) => "elastic tension-only cable (or spring, where tension_only is false)",
    };
    let held = if grounded > 0 {
        format!("{grounded} node(s) on no bar are fixed points (body 'ground').")
    } else if p.pins.is_empty() {
        "No node is off the bars: bar1 is held fixed to remove the rigid motion.".to_string()
    } else {
        String::new()
    };
    let pins = if p.pins.is_empty() {
        String::new()
    } else {
        let at: Vec<&str> = p.pins.iter().map(|(n, _)| n.as_str()).collect();
        format!(
            "\nPinned to the ground (joints pin_<node>, revolute about the given axis or spherical): {}.",
            at.join(", ")
        )
    };
    format!(
        "Imported from {source} (Skelton and de Oliveira's notation) by {by}.\n\
         Node k is n<k> (column k of N); bar i is strut bar<i> on its own body of {} kg, radius {} m; string i is the {kind} string<i> of {} N/m {rest}.\n{held}{pins}",
        said(&p.bar_mass_kg),
        said(&p.bar_radius_m),
        said(&p.string_stiffness_n_per_m),
    )
}
