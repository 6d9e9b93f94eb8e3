//! NTRT's YAML model files (`doc/source/yaml-model-builder.rst` of NTRTsim, and its reader
//! `src/yamlbuilder/TensegrityModel.cpp`) as a testbed scenario.
//!
//! Read as NTRT reads them: the top-level keys `nodes`, `pair_groups`, `builders`,
//! `substructures` and `bond_groups` only; substructures (`a/b/c:` several at once) loaded
//! from their `path` (relative to the file), then rotated (`axis`, `angle` in degrees, about
//! `reference` or the substructure's centroid), scaled about their centroid, offset by
//! `offset` times their place in the `a/b/c` list and translated; builders matched to pairs by
//! tags (a pair's tags are the words of its group name; a builder matches when the pair has
//! all of its words; the last added matching builder wins, rigid ones before strings, so a
//! file's builders override those of its substructures and the defaults `rod` (tgRodInfo,
//! radius 0.5, density 1) and `string` (tgBasicActuatorInfo, stiffness 1000, pretension 0)); `bond_groups` join nodes of adjacent
//! substructures of a `a/b/c/node_node` list; node paths `child.grandchild.node`.
//!
//! Made of it: each rod (tgRodInfo) a strut on a rigid body of mass density x pi r^2 x length
//! (tgRodInfo::getMass), rods sharing a node one body (NTRT compounds them); each string
//! (tgBasicActuatorInfo, tgBasicContactCableInfo, tgKinematicActuatorInfo,
//! tgKinematicContactCableInfo) an elastic tension-only cable of the builder's stiffness whose
//! rest length is the drawn length minus pretension / stiffness (tgSpringCable.cpp:
//! `m_restLength = pos1.distance(pos2) - pretension / coefK`). Everything else is listed as
//! skipped, never dropped silently.

use super::draft::{Draft, DraftBody, DraftCable, DraftError, DraftStrut};
use super::yaml::{self, At, Yaml};
use super::{ImportError, Imported};
use crate::structure::{distance, Vec3};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// Deepest substructure nesting read (a file that includes itself would never end).
const MAX_DEPTH: usize = 16;

/// NTRT's defaults (TensegrityModel.h): rod radius and density, string stiffness and
/// pretension.
const DEFAULT_ROD_RADIUS: f64 = 0.5;
const DEFAULT_ROD_DENSITY: f64 = 1.0;
const DEFAULT_STRING_STIFFNESS: f64 = 1000.0;
const DEFAULT_STRING_PRETENSION: f64 = 0.0;

const ROOT_KEYS: &[&str] = &["nodes", "pair_groups", "builders", "substructures", "bond_groups"];
const CHILD_KEYS: &[&str] = &["path", "rotation", "translation", "scale", "offset"];
const ROD_PARAMS: &[&str] = &["radius", "density", "friction", "roll_friction", "restitution"];
const ACTUATOR_PARAMS: &[&str] = &[
    "stiffness",
    "damping",
    "pretension",
    "history",
    "max_tension",
    "target_velocity",
    "min_actual_length",
    "min_rest_length",
    "rotation",
    "moveCablePointAToEdge",
    "moveCablePointBToEdge",
];
const KINEMATIC_PARAMS: &[&str] = &[
    "stiffness",
    "damping",
    "pretension",
    "radius",
    "motor_friction",
    "motor_inertia",
    "back_drivable",
    "history",
    "max_tension",
    "target_velocity",
    "min_actual_length",
    "min_rest_length",
    "rotation",
];
const BOX_PARAMS: &[&str] = &["width", "height", "density", "friction", "roll_friction", "restitution"];
const SPHERE_PARAMS: &[&str] = &["radius", "density", "friction", "roll_friction", "restitution"];

/// How NTRT's axes become the testbed's.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Axes {
    /// NTRT's y (up) becomes z: (x, y, z) -> (x, -z, y), a rotation of +90 degrees about x.
    ZUp,
    /// Coordinates as written (y up).
    Keep,
}

impl Axes {
    fn map(self, p: Vec3) -> Vec3 {
        match self {
            Axes::ZUp => [p[0], -p[2], p[1]],
            Axes::Keep => p,
        }
    }

    fn said(self) -> &'static str {
        match self {
            Axes::ZUp => "NTRT's y axis (up) is the testbed's z: (x, y, z) in NTRT is (x, -z, y) here",
            Axes::Keep => "NTRT's axes kept as written (y up)",
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Kind {
    Rod,
    String,
    Box,
    Sphere,
}

#[derive(Clone, Debug)]
struct Builder {
    class: String,
    kind: Kind,
    /// Parameter name -> (value as written, place).
    params: BTreeMap<String, (String, At)>,
    file: String,
}

/// A node reference inside a structure: the path of child indices and the node's index.
type NodeRef = (Vec<usize>, usize);

#[derive(Clone, Debug)]
struct Pair {
    a: NodeRef,
    b: NodeRef,
    tags: Vec<String>,
    file: String,
    at: At,
}

/// One file's structure, with its substructures.
#[derive(Clone, Debug, Default)]
struct Sub {
    name: String,
    nodes: Vec<(String, Vec3)>,
    children: Vec<Sub>,
    pairs: Vec<Pair>,
}

impl Sub {
    fn for_each_node(&mut self, f: &mut dyn FnMut(&mut Vec3)) {
        for (_, p) in &mut self.nodes {
            f(p);
        }
        for c in &mut self.children {
            c.for_each_node(f);
        }
    }

    fn centroid(&mut self) -> Vec3 {
        let (mut sum, mut n) = ([0.0; 3], 0.0);
        self.for_each_node(&mut |p| {
            for k in 0..3 {
                sum[k] += p[k];
            }
            n += 1.0;
        });
        sum.map(|s| if n > 0.0 { s / n } else { 0.0 })
    }

    /// NTRT's findNode: breadth first, this structure's nodes before its children's.
    fn find_node(&self, name: &str) -> Option<NodeRef> {
        let mut queue: std::collections::VecDeque<(Vec<usize>, &Sub)> = [(vec![], self)].into();
        while let Some((path, s)) = queue.pop_front() {
            if let Some(i) = s.nodes.iter().position(|(n, _)| n == name) {
                return Some((path, i));
            }
            for (k, c) in s.children.iter().enumerate() {
                let mut p = path.clone();
                p.push(k);
                queue.push_back((p, c));
            }
        }
        None
    }

    fn child_index(&self, name: &str) -> Option<usize> {
        self.children.iter().position(|c| c.name == name)
    }

    /// A node path `child.grandchild.node` (or a bare name found anywhere below).
    fn node_path(&self, path: &str) -> Option<NodeRef> {
        let mut parts: Vec<&str> = path.split('.').collect();
        let node = parts.pop()?;
        let (mut prefix, mut s) = (Vec::new(), self);
        for p in parts {
            let k = s.child_index(p)?;
            prefix.push(k);
            s = &s.children[k];
        }
        let (rest, i) = s.find_node(node)?;
        prefix.extend(rest);
        Some((prefix, i))
    }
}

/// Everything the reading gathers across files.
struct Reader {
    /// (tag, builder) in the order NTRT adds them: the defaults, then each file's after its
    /// substructures'. The last added that matches wins (tgStructureInfo::initRigidInfo and
    /// initConnectorInfo search from the end), rigid builders before strings.
    builders: Vec<(String, Builder)>,
    skipped: Vec<String>,
    /// A string builder that builds a pair gives its pretension.
    pretension_given: bool,
}

fn err(file: &str, at: At, message: impl Into<String>) -> ImportError {
    ImportError::at(file, at, message)
}

fn number(file: &str, y: &Yaml, what: &str) -> Result<f64, ImportError> {
    let s = y.as_str().ok_or_else(|| err(file, y.at(), format!("{what} must be a number")))?;
    match s.trim().parse::<f64>() {
        Ok(x) if x.is_finite() => Ok(x),
        _ => Err(err(file, y.at(), format!("{what} must be a finite number, got '{s}'"))),
    }
}

fn vec3(file: &str, y: &Yaml, what: &str) -> Result<Vec3, ImportError> {
    match y {
        Yaml::Seq(xs, _) if xs.len() == 3 => {
            Ok([number(file, &xs[0], what)?, number(file, &xs[1], what)?, number(file, &xs[2], what)?])
        }
        _ => Err(err(file, y.at(), format!("{what} must be three numbers [x, y, z]"))),
    }
}

fn entries<'a>(file: &str, y: &'a Yaml, what: &str) -> Result<&'a [(Yaml, Yaml)], ImportError> {
    match y {
        Yaml::Map(kv, _) => Ok(kv),
        Yaml::Null(_) => Ok(&[]),
        _ => Err(err(file, y.at(), format!("{what} must be a mapping"))),
    }
}

fn key<'a>(file: &str, k: &'a Yaml) -> Result<&'a str, ImportError> {
    k.as_str().ok_or_else(|| err(file, k.at(), "keys must be plain names"))
}

fn only_keys(file: &str, y: &Yaml, allowed: &[&str], what: &str) -> Result<(), ImportError> {
    for (k, _) in entries(file, y, what)? {
        let name = key(file, k)?;
        if !allowed.contains(&name) {
            return Err(err(
                file,
                k.at(),
                format!("unknown key '{name}' in {what} (expected one of: {})", allowed.join(", ")),
            ));
        }
    }
    Ok(())
}

/// Imports an NTRT YAML file as a scenario; `name` names it.
pub fn import(path: &Path, axes: Axes) -> Result<Imported, ImportError> {
    import_text(path, &super::read_text(path)?, axes)
}

/// Imports NTRT YAML text as a scenario, as if read from `path` (which names it in errors and
/// the scenario; substructures' paths are relative to its directory).
pub fn import_text(path: &Path, text: &str, axes: Axes) -> Result<Imported, ImportError> {
    let mut r = Reader { builders: default_builders(), skipped: Vec::new(), pretension_given: false };
    let top = r.load(path, text, "", 0)?;
    let mut draft = r.draft(path, &top, axes)?;
    let chosen = prestress(&mut draft, r.pretension_given).map_err(|e| ImportError::whole(path, e.to_string()))?;
    draft.description.push_str(&format!("\n{chosen}"));
    let toml = draft.to_toml().map_err(|e| ImportError::whole(path, e.to_string()))?;
    Ok(Imported { toml, skipped: r.skipped, chosen: vec![chosen] })
}

/// The strings' tensions at the drawn state: the file's pretensions where a builder gives
/// one; else (NTRT's default pretension 0 would leave every string slack) the drawn
/// structure's self-stress, its least tension [`super::DEFAULT_LEAST_TENSION_N`], or that
/// tension on every string when the drawing has no self-stress with every string taut. What
/// was chosen, in a sentence.
fn prestress(draft: &mut Draft, pretension_given: bool) -> Result<String, DraftError> {
    if pretension_given {
        return Ok("prestress: the file's pretensions (rest length = drawn - pretension / stiffness).".into());
    }
    let least = super::DEFAULT_LEAST_TENSION_N;
    if let Some(c) = super::self_stress::prestress(draft, least)? {
        return Ok(format!(
            "{} (the file gives no pretension; NTRT's default 0 leaves every string slack).",
            c.sentence
        ));
    }
    let positions: Vec<(String, Vec3)> = draft.bodies.iter().flat_map(|b| b.nodes.clone()).collect();
    let pos = |n: &str| positions.iter().find(|(m, _)| m == n).map(|(_, p)| *p).unwrap_or_default();
    for c in &mut draft.cables {
        let (Some(k), drawn) = (c.stiffness_n_per_m, distance(pos(&c.a), pos(&c.b))) else { continue };
        c.length_m = drawn - least / k;
        if c.length_m.is_nan() || c.length_m <= 0.0 {
            return Err(DraftError::TensionNoRest {
                string: c.name.clone(),
                tension_n: least,
                stiffness_n_per_m: k,
                drawn_m: drawn,
            });
        }
    }
    Ok(format!(
        "prestress: the file gives no pretension and the drawing has no self-stress with every string in tension, so every \
         string is at {least} N at the drawn state, which is then no equilibrium: the structure moves, and the run fails if \
         it loses its prestress."
    ))
}

fn default_builders() -> Vec<(String, Builder)> {
    let b =
        |class: &str, kind| Builder { class: class.into(), kind, params: BTreeMap::new(), file: "(default)".into() };
    [
        ("rod".to_string(), b("tgRodInfo", Kind::Rod)),
        ("string".to_string(), b("tgBasicActuatorInfo", Kind::String)),
        ("box".to_string(), b("tgBoxInfo", Kind::Box)),
        ("sphere".to_string(), b("tgSphereInfo", Kind::Sphere)),
    ]
    .into()
}

impl Kind {
    /// Rods, boxes and spheres: NTRT tries these builders on a pair before the strings.
    fn rigid(self) -> bool {
        !matches!(self, Kind::String)
    }
}

impl Reader {
    /// One file and its substructures, in NTRT's order: substructures, builders, nodes, pair
    /// groups, bond groups.
    fn load(&mut self, path: &Path, text: &str, name: &str, depth: usize) -> Result<Sub, ImportError> {
        let file = path.display().to_string();
        if depth > MAX_DEPTH {
            return Err(ImportError {
                file,
                line: 0,
                col: 0,
                message: format!("substructures nest deeper than {MAX_DEPTH} levels (does a file include itself?)"),
            });
        }
        let root = yaml::parse(text).map_err(|e| err(&file, e.at, e.message))?;
        only_keys(&file, &root, ROOT_KEYS, "an NTRT model file")?;
        let mut sub = Sub { name: name.into(), ..Default::default() };
        if let Some(c) = root.get("substructures") {
            self.substructures(&file, path, c, &mut sub, depth)?;
        }
        if let Some(b) = root.get("builders") {
            self.add_builders(&file, b)?;
        }
        if let Some(n) = root.get("nodes") {
            for (k, v) in entries(&file, n, "nodes")? {
                let node = key(&file, k)?;
                if sub.nodes.iter().any(|(m, _)| m == node) {
                    return Err(err(&file, k.at(), format!("duplicate node '{node}'")));
                }
                sub.nodes.push((node.to_string(), vec3(&file, v, &format!("node '{node}'"))?));
            }
        }
        if let Some(g) = root.get("pair_groups") {
            for (k, pairs) in entries(&file, g, "pair_groups")? {
                let tags = key(&file, k)?.to_string();
                self.pairs(&file, &mut sub, &tags, pairs, None)?;
            }
        }
        if let Some(g) = root.get("bond_groups") {
            self.bond_groups(&file, &mut sub, g)?;
        }
        Ok(sub)
    }

    /// `substructures`: loads each child, then rotates all, then scales, offsets and translates.
    fn substructures(
        &mut self,
        file: &str,
        path: &Path,
        y: &Yaml,
        sub: &mut Sub,
        depth: usize,
    ) -> Result<(), ImportError> {
        let dir = path.parent().unwrap_or(Path::new("."));
        let list = entries(file, y, "substructures")?;
        for (k, attrs) in list {
            only_keys(file, attrs, CHILD_KEYS, "a substructure")?;
            let p = attrs.get("path").ok_or_else(|| err(file, k.at(), "a substructure needs a path"))?;
            let p = p.as_str().ok_or_else(|| err(file, p.at(), "path must be a file name"))?;
            let child_path: PathBuf = if Path::new(p).is_absolute() { p.into() } else { dir.join(p) };
            for name in key(file, k)?.split('/') {
                if sub.child_index(name).is_some() {
                    return Err(err(file, k.at(), format!("duplicate substructure '{name}'")));
                }
                // A child file that cannot be read is an error at the parent's key.
                let child = super::read_text(&child_path)
                    .and_then(|text| self.load(&child_path, &text, name, depth + 1))
                    .map_err(|e| {
                        if e.line == 0 && e.file == child_path.display().to_string() {
                            err(file, k.at(), format!("substructure '{name}' ({}): {}", e.file, e.message))
                        } else {
                            e
                        }
                    })?;
                sub.children.push(child);
            }
        }
        for (k, attrs) in list {
            if let Some(rot) = attrs.get("rotation") {
                for name in key(file, k)?.split('/') {
                    let i = sub.child_index(name).expect("added above");
                    rotate(file, rot, &mut sub.children[i])?;
                }
            }
        }
        for (k, attrs) in list {
            for (index, name) in key(file, k)?.split('/').enumerate() {
                let i = sub.child_index(name).expect("added above");
                let c = &mut sub.children[i];
                if let Some(s) = attrs.get("scale") {
                    let f = number(file, s, "scale")?;
                    let centre = c.centroid();
                    c.for_each_node(&mut |p| *p = [0, 1, 2].map(|j| centre[j] + f * (p[j] - centre[j])));
                }
                let mut shift = [0.0; 3];
                if let Some(o) = attrs.get("offset") {
                    let o = vec3(file, o, "offset")?;
                    shift = o.map(|x| x * index as f64);
                }
                if let Some(t) = attrs.get("translation") {
                    let t = vec3(file, t, "translation")?;
                    shift = [0, 1, 2].map(|j| shift[j] + t[j]);
                }
                c.for_each_node(&mut |p| *p = [0, 1, 2].map(|j| p[j] + shift[j]));
            }
        }
        Ok(())
    }

    fn add_builders(&mut self, file: &str, y: &Yaml) -> Result<(), ImportError> {
        for (k, v) in entries(file, y, "builders")? {
            let tag = key(file, k)?.to_string();
            only_keys(file, v, &["class", "parameters"], "a builder")?;
            let class_y = v.get("class").ok_or_else(|| err(file, k.at(), format!("builder '{tag}' needs a class")))?;
            let class = class_y.as_str().unwrap_or_default().to_string();
            let (kind, allowed) = match class.as_str() {
                "tgRodInfo" => (Kind::Rod, ROD_PARAMS),
                "tgBasicActuatorInfo" | "tgBasicContactCableInfo" => (Kind::String, ACTUATOR_PARAMS),
                "tgKinematicActuatorInfo" | "tgKinematicContactCableInfo" => (Kind::String, KINEMATIC_PARAMS),
                "tgBoxInfo" => (Kind::Box, BOX_PARAMS),
                "tgSphereInfo" => (Kind::Sphere, SPHERE_PARAMS),
                _ => return Err(err(file, class_y.at(), format!("unsupported builder class '{class}' (NTRT's YAML builder knows tgRodInfo, tgBasicActuatorInfo, tgBasicContactCableInfo, tgKinematicActuatorInfo, tgKinematicContactCableInfo, tgBoxInfo, tgSphereInfo)"))),
            };
            let mut params = BTreeMap::new();
            if let Some(p) = v.get("parameters") {
                for (pk, pv) in entries(file, p, "parameters")? {
                    let name = key(file, pk)?;
                    if !allowed.contains(&name) {
                        return Err(err(
                            file,
                            pk.at(),
                            format!("unsupported {class} parameter '{name}' (expected one of: {})", allowed.join(", ")),
                        ));
                    }
                    let value =
                        pv.as_str().ok_or_else(|| err(file, pv.at(), format!("parameter '{name}' must be a value")))?;
                    params.insert(name.to_string(), (value.to_string(), pv.at()));
                }
            }
            self.builders.push((tag, Builder { class, kind, params, file: file.into() }));
        }
        Ok(())
    }

    /// The pairs of one group (`tags`), resolved in `sub`, or between two children for a bond.
    fn pairs(
        &mut self,
        file: &str,
        sub: &mut Sub,
        tags: &str,
        y: &Yaml,
        bond: Option<(usize, usize)>,
    ) -> Result<(), ImportError> {
        let Yaml::Seq(items, _) = y else {
            return Err(err(file, y.at(), format!("the pairs of '{tags}' must be a list of [node, node]")));
        };
        for item in items {
            let ends = match item {
                Yaml::Seq(xs, _) if xs.len() == 2 => [&xs[0], &xs[1]],
                _ => return Err(err(file, item.at(), "a pair is two node names [a, b]")),
            };
            let mut refs = Vec::new();
            for (side, e) in ends.iter().enumerate() {
                let name = e.as_str().ok_or_else(|| err(file, e.at(), "a node name"))?;
                let found = match bond {
                    None => sub.node_path(name),
                    Some(children) => {
                        let c = if side == 0 { children.0 } else { children.1 };
                        sub.children[c].node_path(name).map(|(mut p, i)| {
                            p.insert(0, c);
                            (p, i)
                        })
                    }
                };
                refs.push(found.ok_or_else(|| err(file, e.at(), format!("unknown node '{name}'")))?);
            }
            let mut words: Vec<String> = tags.split_whitespace().map(str::to_string).collect();
            if let Some((a, b)) = bond {
                let (na, nb) = (sub.children[a].name.clone(), sub.children[b].name.clone());
                words.extend([na.clone(), nb.clone(), format!("{na}/{nb}")]);
            }
            let b = refs.pop().expect("two ends");
            let a = refs.pop().expect("two ends");
            sub.pairs.push(Pair { a, b, tags: words, file: file.into(), at: item.at() });
        }
        Ok(())
    }

    /// `bond_groups`: tag -> bond -> pairs, or bond -> tag -> pairs; a bond `a/b/c/node_node`
    /// joins each two adjacent substructures of its list.
    fn bond_groups(&mut self, file: &str, sub: &mut Sub, y: &Yaml) -> Result<(), ImportError> {
        for (k1, v1) in entries(file, y, "bond_groups")? {
            let first = key(file, k1)?;
            for (k2, pairs) in entries(file, v1, "a bond group")? {
                let second = key(file, k2)?;
                let (tags, bond, at) = match (first.contains('/'), second.contains('/')) {
                    (false, true) => (first, second, k2.at()),
                    (true, false) => (second, first, k1.at()),
                    _ => {
                        return Err(err(
                            file,
                            k2.at(),
                            "a bond group nests a tag and a bond (a/b/node_node), one in the other",
                        ))
                    }
                };
                let mut parts: Vec<&str> = bond.split('/').collect();
                let kind = parts.pop().unwrap_or_default();
                if parts.len() < 2 {
                    return Err(err(file, at, "a bond joins two or more substructures: a/b/node_node"));
                }
                if kind == "node_edge" {
                    self.skipped.push(format!("{file}:{}:{}: node_edge bond '{bond}' (NTRT moves the substructures to hang a node on a string's midpoint): not imported", at.line, at.col));
                    continue;
                }
                if kind != "node_node" {
                    return Err(err(file, at, format!("unsupported bond type '{kind}' (node_node or node_edge)")));
                }
                for w in parts.windows(2) {
                    let find = |n: &str| {
                        sub.child_index(n).ok_or_else(|| err(file, at, format!("unknown substructure '{n}'")))
                    };
                    let (a, b) = (find(w[0])?, find(w[1])?);
                    self.pairs(file, sub, tags, pairs, Some((a, b)))?;
                }
            }
        }
        Ok(())
    }
}

/// Rotates a substructure about `reference` (default its centroid) by `angle` degrees about
/// `axis` (Rodrigues' formula).
fn rotate(file: &str, rot: &Yaml, c: &mut Sub) -> Result<(), ImportError> {
    only_keys(file, rot, &["axis", "angle", "reference"], "a rotation")?;
    let (Some(axis), Some(angle)) = (rot.get("axis"), rot.get("angle")) else {
        return Ok(()); // NTRT ignores a rotation without both
    };
    let axis = vec3(file, axis, "rotation axis")?;
    let norm = crate::structure::norm(axis);
    if norm.is_nan() || norm <= 0.0 {
        return Err(err(file, rot.at(), "the rotation axis must not be zero"));
    }
    let theta = number(file, angle, "rotation angle")?.to_radians();
    let reference = match rot.get("reference") {
        Some(r) => vec3(file, r, "rotation reference")?,
        None => c.centroid(),
    };
    c.for_each_node(&mut |p| {
        let v = [p[0] - reference[0], p[1] - reference[1], p[2] - reference[2]];
        let turned = crate::structure::rotated(v, axis, theta);
        *p = [0, 1, 2].map(|k| reference[k] + turned[k]);
    });
    Ok(())
}

/// A flattened node: its name (`child.node` below the top level) and position.
struct FlatNode {
    name: String,
    position: Vec3,
}

/// All nodes, depth first, with their references from the top structure; all pairs with
/// references from the top.
fn flatten(sub: &Sub, prefix: &[usize], names: &[String], nodes: &mut Vec<(NodeRef, FlatNode)>, pairs: &mut Vec<Pair>) {
    for (i, (n, p)) in sub.nodes.iter().enumerate() {
        let mut full = names.to_vec();
        full.push(n.clone());
        nodes.push(((prefix.to_vec(), i), FlatNode { name: full.join("."), position: *p }));
    }
    for pair in &sub.pairs {
        let lift = |r: &NodeRef| -> NodeRef {
            let mut p = prefix.to_vec();
            p.extend(r.0.iter().copied());
            (p, r.1)
        };
        pairs.push(Pair { a: lift(&pair.a), b: lift(&pair.b), ..pair.clone() });
    }
    for (k, c) in sub.children.iter().enumerate() {
        let mut p = prefix.to_vec();
        p.push(k);
        let mut n = names.to_vec();
        n.push(c.name.clone());
        flatten(c, &p, &n, nodes, pairs);
    }
}

impl Reader {
    /// The builder a pair's tags select, as NTRT selects it: a builder matches when every word
    /// of its tag is among the pair's tags; the last added rigid builder that matches, else the
    /// last added string builder. Its index in [`Reader::builders`].
    fn builder_for(&self, pair: &Pair) -> Option<usize> {
        let matches = |(_, (tag, _)): &(usize, &(String, Builder))| {
            tag.split_whitespace().all(|w| pair.tags.iter().any(|t| t == w))
        };
        let last = |rigid: bool| {
            self.builders.iter().enumerate().rev().filter(|(_, (_, b))| b.kind.rigid() == rigid).find(matches)
        };
        last(true).or_else(|| last(false)).map(|(i, _)| i)
    }

    fn param(&self, b: &Builder, name: &str, default: f64) -> Result<f64, ImportError> {
        match b.params.get(name) {
            None => Ok(default),
            Some((v, at)) => match v.trim().parse::<f64>() {
                Ok(x) if x.is_finite() => Ok(x),
                _ => Err(err(&b.file, *at, format!("{name} must be a finite number, got '{v}'"))),
            },
        }
    }

    /// Lists each builder's parameters that the testbed does not model (once per builder).
    fn note_unmodelled(&mut self, tag: &str, b: &Builder, used: &[&str]) {
        let unused: Vec<String> = b
            .params
            .iter()
            .filter(|(k, _)| !used.contains(&k.as_str()))
            .map(|(k, (v, _))| format!("{k} = {v}"))
            .collect();
        if !unused.is_empty() {
            self.skipped.push(format!("builder '{tag}' ({}): {} (not modelled)", b.class, unused.join(", ")));
        }
    }

    fn draft(&mut self, path: &Path, top: &Sub, axes: Axes) -> Result<Draft, ImportError> {
        let (mut nodes, mut pairs) = (Vec::new(), Vec::new());
        flatten(top, &[], &[], &mut nodes, &mut pairs);
        let index: BTreeMap<NodeRef, usize> = nodes.iter().enumerate().map(|(i, (r, _))| (r.clone(), i)).collect();
        let pos = |i: usize| axes.map(nodes[i].1.position);
        let (mut rods, mut strings) = (Vec::new(), Vec::new());
        let mut noted = std::collections::BTreeSet::new();
        for pair in &pairs {
            let (a, b) = (index[&pair.a], index[&pair.b]);
            let Some(index) = self.builder_for(pair) else {
                self.skipped.push(format!(
                    "{}:{}:{}: pair {}-{} (tags '{}') matches no builder: not built, as in NTRT",
                    pair.file,
                    pair.at.line,
                    pair.at.col,
                    nodes[a].1.name,
                    nodes[b].1.name,
                    pair.tags.join(" ")
                ));
                continue;
            };
            let (tag, builder) = self.builders[index].clone();
            let l = distance(pos(a), pos(b));
            if l <= 0.0 {
                return Err(err(
                    &pair.file,
                    pair.at,
                    format!("pair {}-{} has zero length", nodes[a].1.name, nodes[b].1.name),
                ));
            }
            match builder.kind {
                Kind::Rod => {
                    if noted.insert(index) {
                        self.note_unmodelled(&tag, &builder, &["radius", "density"]);
                    }
                    let (r, mass) = self.rod(pair, &builder, l, (&nodes[a].1.name, &nodes[b].1.name))?;
                    rods.push((a, b, r, mass));
                }
                Kind::String => {
                    self.pretension_given |= builder.params.contains_key("pretension");
                    if noted.insert(index) {
                        self.note_unmodelled(&tag, &builder, &["stiffness", "pretension"]);
                    }
                    let (k, rest) = self.string(pair, (&tag, &builder), l, (&nodes[a].1.name, &nodes[b].1.name))?;
                    strings.push((a, b, tag, k, rest));
                }
                Kind::Box | Kind::Sphere => self.skipped.push(format!(
                    "{}:{}:{}: {} '{}' between {} and {}: not modelled by the testbed",
                    pair.file, pair.at.line, pair.at.col, builder.class, tag, nodes[a].1.name, nodes[b].1.name
                )),
            }
        }
        let names: Vec<String> = nodes.iter().map(|(_, n)| n.name.clone()).collect();
        self.note_spheres(&names);
        let positions: Vec<Vec3> = (0..nodes.len()).map(pos).collect();
        self.assemble(path, axes, &names, &positions, &rods, &strings)
    }

    /// A rod builder's radius [m] and mass [kg] for a pair of drawn length `l` [m] between
    /// the nodes named `ends`.
    fn rod(&self, pair: &Pair, builder: &Builder, l: f64, ends: (&str, &str)) -> Result<(f64, f64), ImportError> {
        let r = self.param(builder, "radius", DEFAULT_ROD_RADIUS)?;
        let rho = self.param(builder, "density", DEFAULT_ROD_DENSITY)?;
        // tgRodInfo::getMass: volume pi r^2 L times density.
        let mass = rho * std::f64::consts::PI * r * r * l;
        if mass.is_nan() || mass <= 0.0 {
            let message = format!("rod {}-{} has no mass (density {rho}, radius {r})", ends.0, ends.1);
            return Err(err(&pair.file, pair.at, message));
        }
        Ok((r, mass))
    }

    /// A string builder's stiffness [N/m] and rest length [m] for a pair of drawn length `l`
    /// [m] between the nodes named `ends`.
    fn string(
        &self,
        pair: &Pair,
        (tag, builder): (&str, &Builder),
        l: f64,
        ends: (&str, &str),
    ) -> Result<(f64, f64), ImportError> {
        let k = self.param(builder, "stiffness", DEFAULT_STRING_STIFFNESS)?;
        let p = self.param(builder, "pretension", DEFAULT_STRING_PRETENSION)?;
        let at = builder.params.get("stiffness").map_or(pair.at, |(_, at)| *at);
        if k.is_nan() || k <= 0.0 {
            return Err(err(&builder.file, at, format!("builder '{tag}': stiffness must be > 0, got {k}")));
        }
        // tgSpringCable.cpp: rest length = drawn length - pretension / stiffness.
        let rest = l - p / k;
        if rest.is_nan() || rest <= 0.0 {
            let message = format!(
                "string {}-{}: pretension {p} at stiffness {k} leaves no rest length (drawn {l})",
                ends.0, ends.1
            );
            return Err(err(&pair.file, pair.at, message));
        }
        Ok((k, rest))
    }

    /// Sphere builders whose tag names a node: said skipped.
    fn note_spheres(&mut self, names: &[String]) {
        for (tag, b) in &self.builders {
            if b.kind == Kind::Sphere
                && b.file != "(default)"
                && names.iter().any(|n| n.rsplit('.').next() == Some(tag.as_str()))
            {
                self.skipped.push(format!("sphere node '{tag}' ({}): not modelled by the testbed", b.class));
            }
        }
    }

    /// Bodies (rods sharing nodes joined, the first held fixed), struts and cables.
    fn assemble(
        &mut self,
        path: &Path,
        axes: Axes,
        names: &[String],
        positions: &[Vec3],
        rods: &[(usize, usize, f64, f64)],
        strings: &[(usize, usize, String, f64, f64)],
    ) -> Result<Draft, ImportError> {
        let file = path.display().to_string();
        if rods.is_empty() {
            return Err(ImportError {
                file,
                line: 0,
                col: 0,
                message: "the model has no rod (tgRodInfo): nothing rigid to build".into(),
            });
        }
        let bodies = rod_bodies(names.len(), rods);
        let mut body_of = vec![None; names.len()];
        let mut draft = Draft {
            name: format!(
                "{} (from NTRT)",
                path.file_stem().map(|s| s.to_string_lossy().to_string()).unwrap_or_default()
            ),
            ..Default::default()
        };
        for (bi, members) in bodies.iter().enumerate() {
            let mut ends: Vec<usize> = members.iter().flat_map(|&r| [rods[r].0, rods[r].1]).collect();
            ends.sort();
            ends.dedup();
            for &n in &ends {
                body_of[n] = Some(bi);
            }
            let (mass, inertia) = rod_inertia(
                members.iter().map(|&r| (positions[rods[r].0], positions[rods[r].1], rods[r].2, rods[r].3)),
            );
            let first = members[0];
            draft.bodies.push(DraftBody {
                name: format!("rod {}-{}", names[rods[first].0], names[rods[first].1]),
                fixed: bi == 0,
                mass_kg: mass,
                inertia_kg_m2: Some([inertia; 3]),
                nodes: ends.iter().map(|&n| (names[n].clone(), positions[n])).collect(),
            });
        }
        for &(a, b, r, _) in rods {
            draft.struts.push(DraftStrut {
                name: format!("rod {}-{}", names[a], names[b]),
                a: names[a].clone(),
                b: names[b].clone(),
                radius_m: r,
            });
        }
        add_string_cables(&mut draft, &file, names, &body_of, strings)?;
        for (n, name) in names.iter().enumerate() {
            if body_of[n].is_none() && !strings.iter().any(|s| s.0 == n || s.1 == n) {
                self.skipped.push(format!("node '{name}': on no rod and no string"));
            }
        }
        draft.description = self.description(&file, axes, &draft);
        Ok(draft)
    }

    fn description(&self, file: &str, axes: Axes, d: &Draft) -> String {
        let mut s = format!(
            "Imported from the NTRT model {file} by `tensegrity import ntrt`.\n\
             Axes: {}. Units: NTRT's numbers taken as SI (m, kg/m^3, N/m, N).\n\
             {} rods as struts on {} rigid bodies (mass = density pi r^2 length, tgRodInfo; isotropic inertia, which an equilibrium does not depend on); body '{}' is held fixed to remove the rigid motion.\n\
             {} strings as elastic tension-only cables (the builder's stiffness; rest length = drawn length - pretension / stiffness, as NTRT's tgSpringCable).\n\
             Not in the file, so not here: NTRT's world (ground, gravity) and its controllers and motors.\n\
             Cable ends are at the nodes (NTRT's moveCablePointAToEdge puts them on the rod's surface).",
            axes.said(),
            d.struts.len(),
            d.bodies.len(),
            d.bodies.first().map(|b| b.name.as_str()).unwrap_or(""),
            d.cables.len()
        );
        if !self.skipped.is_empty() {
            s.push_str("\nSkipped:");
            for k in &self.skipped {
                s.push_str("\n- ");
                s.push_str(k);
            }
        }
        s
    }
}

/// Rods joined into bodies where they share a node (NTRT compounds such rods): lists of rod
/// indices, in order of their first rod.
fn rod_bodies(n_nodes: usize, rods: &[(usize, usize, f64, f64)]) -> Vec<Vec<usize>> {
    let mut parent: Vec<usize> = (0..n_nodes).collect();
    fn find(p: &mut [usize], mut x: usize) -> usize {
        while p[x] != x {
            p[x] = p[p[x]];
            x = p[x];
        }
        x
    }
    for &(a, b, _, _) in rods {
        let (ra, rb) = (find(&mut parent, a), find(&mut parent, b));
        parent[ra] = rb;
    }
    let mut groups: Vec<(usize, Vec<usize>)> = Vec::new();
    for (i, &(a, _, _, _)) in rods.iter().enumerate() {
        let root = find(&mut parent, a);
        match groups.iter_mut().find(|(r, _)| *r == root) {
            Some((_, g)) => g.push(i),
            None => groups.push((root, vec![i])),
        }
    }
    groups.into_iter().map(|(_, g)| g).collect()
}

/// Mass and an isotropic moment of inertia of rods (ends, radius, mass) joined in one body:
/// each rod's transverse moment m (3 r^2 + L^2) / 12 about its middle, moved to the body's
/// centre of mass.
fn rod_inertia(rods: impl Iterator<Item = (Vec3, Vec3, f64, f64)> + Clone) -> (f64, f64) {
    let mass: f64 = rods.clone().map(|r| r.3).sum();
    let mid = |a: Vec3, b: Vec3| [0, 1, 2].map(|k| 0.5 * (a[k] + b[k]));
    let com = [0, 1, 2].map(|k| rods.clone().map(|(a, b, _, m)| m * mid(a, b)[k]).sum::<f64>() / mass);
    let inertia = rods
        .map(|(a, b, r, m)| {
            let l = distance(a, b);
            let d = distance(mid(a, b), com);
            m * (3.0 * r * r + l * l) / 12.0 + m * d * d
        })
        .sum();
    (mass, inertia)
}

/// Each string an elastic cable between two rods' nodes, named `TAG A-B` (with ` ~2`, ` ~3`
/// after a name already taken); a string end on no rod is an error.
fn add_string_cables(
    draft: &mut Draft,
    file: &str,
    names: &[String],
    body_of: &[Option<usize>],
    strings: &[(usize, usize, String, f64, f64)],
) -> Result<(), ImportError> {
    let mut used = std::collections::BTreeSet::new();
    for (a, b, tag, k, rest) in strings {
        for n in [*a, *b] {
            if body_of[n].is_none() {
                return Err(ImportError {
                    file: file.to_string(),
                    line: 0,
                    col: 0,
                    message: format!("string end '{}' is on no rod: NTRT anchors strings to rigid bodies", names[n]),
                });
            }
        }
        let mut name = format!("{tag} {}-{}", names[*a], names[*b]);
        let base = name.clone();
        let mut i = 2;
        while !used.insert(name.clone()) {
            name = format!("{base} ~{i}");
            i += 1;
        }
        draft.cables.push(DraftCable {
            through: Vec::new(),
            name,
            a: names[*a].clone(),
            b: names[*b].clone(),
            stiffness_n_per_m: Some(*k),
            length_m: *rest,
            tension_only: true,
        });
    }
    Ok(())
}
