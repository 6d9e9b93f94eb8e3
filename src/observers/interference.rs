//! Member interference, every tick: struts are capsules (a segment and a radius), and so are
//! cables and springs (tendons, thinner); two members interfere when the distance between their
//! segments is below the sum of their radii: two struts through each other, a cable through a
//! strut, two cables through each other.
//!
//! Broad phase: parry's bounding volume hierarchy over the capsules' boxes, inflated by the
//! margin, so that only nearby pairs reach the narrow phase. Narrow phase: parry's closed-form
//! segment-segment closest points; clearance = segment distance - r1 - r2 (negative: overlap).
//!
//! Pairs that touch by construction are excluded (see [`attached_pairs`]): members sharing a
//! node, members whose endpoints coincide in the initial configuration (a joint), and a member
//! whose endpoint sits on a body of the other member inside that member's capsule (a cable
//! attached along a strut). The scenario may list further pairs.

use super::{Note, Observer, SettlePoint, Tick};
use crate::report::{InterferenceReport, InterferenceViolation, PairClearanceReport, PointReport, ScenarioReport};
use crate::settings::InterferenceSettings;
use crate::structure::{distance, MemberKind, NodeId, Structure, Vec3};
use parry3d_f64::bounding_volume::{Aabb, BoundingVolume};
use parry3d_f64::math::Vector;
use parry3d_f64::partitioning::{Bvh, BvhBuildStrategy};
use parry3d_f64::query::details::closest_points_segment_segment_with_locations_nD;
use std::collections::{BTreeMap, HashSet};

/// The time series of the smallest clearance at each tick (in the recording).
const MIN_CLEARANCE_SERIES: &str = "interference/min_clearance_m";

/// Endpoints closer than this fraction of the structure's size count as the same joint.
const COINCIDENT_FRACTION: f64 = 1e-9;

/// One capsule: segment ends \[m\] and radius \[m\].
pub type Capsule = ([f64; 3], [f64; 3], f64);

/// A measured pair: indices (i < j), clearance \[m\] and the closest points on the two axes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PairClearance {
    pub i: usize,
    pub j: usize,
    pub clearance_m: f64,
    pub points: [[f64; 3]; 2],
}

/// One straight segment of a member as the checks see it: a capsule between two nodes. A
/// clustered cable gives one per segment of its path, each named by the cable.
#[derive(Clone, Debug, PartialEq)]
pub struct Segment {
    pub name: String,
    /// "strut", "cable" or "spring".
    pub kind: &'static str,
    pub a: NodeId,
    pub b: NodeId,
    pub radius_m: f64,
}

/// The segments checked: every strut's, then (with `tendons`) every cable's and spring's.
pub fn members(s: &Structure, tendons: bool) -> Vec<Segment> {
    let kinds: &[MemberKind] =
        if tendons { &[MemberKind::Strut, MemberKind::Cable, MemberKind::Spring] } else { &[MemberKind::Strut] };
    let mut out = Vec::new();
    for &kind in kinds {
        for (_, m) in s.members_of(kind) {
            let segment = |(a, b)| Segment { name: m.name.clone(), kind: kind.label(), a, b, radius_m: m.radius_m };
            out.extend(m.segments().map(segment));
        }
    }
    out
}

fn vec3(a: [f64; 3]) -> Vector {
    Vector::new(a[0], a[1], a[2])
}

/// Distance from point `p` to the segment `a`-`b` [m].
fn point_segment_distance(p: Vec3, a: Vec3, b: Vec3) -> f64 {
    let (p, a, b) = (vec3(p), vec3(a), vec3(b));
    let ab = b - a;
    let t = if ab.length_squared() > 0.0 { ((p - a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0) } else { 0.0 };
    (a + ab * t - p).length()
}

/// The pairs (i < j) of `members` that touch by construction in the initial configuration:
/// a shared node, coinciding endpoints (within `COINCIDENT_FRACTION` of the structure's size),
/// or an endpoint of one on a body that carries the other, inside the other's capsule.
pub fn attached_pairs(s: &Structure, members: &[Segment]) -> HashSet<(usize, usize)> {
    let size = crate::structure::structure_size(s);
    let pos = |n: NodeId| s.nodes[n].position;
    let body = |n: NodeId| s.nodes[n].body;
    let mut out = HashSet::new();
    for i in 0..members.len() {
        for j in i + 1..members.len() {
            let (m, o) = (&members[i], &members[j]);
            let touches = |m: &Segment, o: &Segment| {
                [m.a, m.b].iter().any(|&p| {
                    [o.a, o.b].iter().any(|&q| p == q || distance(pos(p), pos(q)) <= COINCIDENT_FRACTION * size)
                        || ((body(p) == body(o.a) || body(p) == body(o.b))
                            && point_segment_distance(pos(p), pos(o.a), pos(o.b)) <= m.radius_m + o.radius_m)
                })
            };
            if touches(m, o) || touches(o, m) {
                out.insert((i, j));
            }
        }
    }
    out
}

/// Up to this many capsules every pair is tested directly (boxes first); above it a bounding
/// volume hierarchy finds the candidate pairs. Building the hierarchy every tick costs more
/// than the direct test below a few dozen members (measured: 13 us a tick for the 12 members
/// of the 3-strut prism with the hierarchy).
const DIRECT_PAIRS_MAX_CAPSULES: usize = 48;

/// Clearance of every pair of capsules closer than `margin_m`, except the excluded ones.
pub fn clearances(capsules: &[Capsule], margin_m: f64, excluded: impl Fn(usize, usize) -> bool) -> Vec<PairClearance> {
    if capsules.len() < 2 {
        return Vec::new();
    }
    let half = 0.5 * margin_m;
    let boxes: Vec<Aabb> = capsules
        .iter()
        .map(|(a, b, r)| {
            let (a, b) = (vec3(*a), vec3(*b));
            let pad = Vector::splat(r + half);
            Aabb::new(a.min(b) - pad, a.max(b) + pad)
        })
        .collect();
    let mut out = Vec::new();
    let mut test = |i: usize, j: usize| {
        if i < j && !excluded(i, j) {
            if let Some(p) = pair_clearance(capsules, i, j, margin_m) {
                out.push(p);
            }
        }
    };
    if capsules.len() <= DIRECT_PAIRS_MAX_CAPSULES {
        for i in 0..capsules.len() {
            for j in i + 1..capsules.len() {
                if boxes[i].intersects(&boxes[j]) {
                    test(i, j);
                }
            }
        }
    } else {
        let bvh = Bvh::from_leaves(BvhBuildStrategy::Binned, &boxes);
        for (i, j) in bvh.leaf_pairs(&bvh, |n1, n2| n1.intersects(n2)) {
            test(i as usize, j as usize);
        }
    }
    out.sort_by_key(|p| (p.i, p.j));
    out
}

/// The clearance of capsules `i` and `j` (segment distance minus both radii) and the closest
/// points on their axes, when it is within `margin_m`.
fn pair_clearance(capsules: &[Capsule], i: usize, j: usize, margin_m: f64) -> Option<PairClearance> {
    let (a1, b1, r1) = capsules[i];
    let (a2, b2, r2) = capsules[j];
    let (a1, b1, a2, b2) = (vec3(a1), vec3(b1), vec3(a2), vec3(b2));
    let (l1, l2) = closest_points_segment_segment_with_locations_nD((&a1, &b1), (&a2, &b2));
    let s1 = parry3d_f64::shape::Segment::new(a1, b1);
    let s2 = parry3d_f64::shape::Segment::new(a2, b2);
    let (p1, p2) = (s1.point_at(&l1), s2.point_at(&l2));
    let clearance_m = (p1 - p2).length() - r1 - r2;
    (clearance_m <= margin_m).then_some(PairClearance {
        i,
        j,
        clearance_m,
        points: [[p1.x, p1.y, p1.z], [p2.x, p2.y, p2.z]],
    })
}

#[derive(Clone, Debug)]
struct PairStats {
    min_clearance_m: f64,
    tick_of_min: u64,
    points_at_min: [[f64; 3]; 2],
    /// Open violation interval (first, last tick).
    open: Option<(u64, u64)>,
    /// Closed violation intervals, each with its minimum clearance and closest points.
    violations: Vec<InterferenceViolation>,
    /// Minimum within the open interval.
    open_min: (f64, u64, [[f64; 3]; 2]),
}

/// The interference observer.
pub struct Interference {
    settings: InterferenceSettings,
    members: Vec<Segment>,
    excluded: HashSet<(usize, usize)>,
    pairs_checked: usize,
    stats: BTreeMap<(usize, usize), PairStats>,
    ticks: u64,
}

impl Interference {
    /// Sets up the pairs for `s`. Unknown member names in `exclude` are an error.
    pub fn new(s: &Structure, settings: &InterferenceSettings) -> Result<Self, crate::settings::UnknownMember> {
        settings.check_member_names(s)?;
        let members = if settings.enabled { members(s, settings.tendons) } else { Vec::new() };
        let mut excluded = attached_pairs(s, &members);
        let id = |name: &str| members.iter().position(|t| t.name == name);
        for (a, b) in &settings.exclude {
            if let (Some(i), Some(j)) = (id(a), id(b)) {
                excluded.insert((i.min(j), i.max(j)));
            }
        }
        let n = members.len();
        let pairs_checked = n * n.saturating_sub(1) / 2 - excluded.iter().filter(|(i, j)| i != j).count();
        let mut observer = Interference {
            settings: settings.clone(),
            members,
            excluded,
            pairs_checked,
            stats: BTreeMap::new(),
            ticks: 0,
        };
        if settings.enabled {
            // Tick 0, the structure as drawn: members drawn through each other interfere before
            // any settling method (the static relaxation's first step among them) moves them.
            let drawn: Vec<[f64; 3]> = s.nodes.iter().map(|n| n.position).collect();
            observer.check(0, &drawn, &mut Vec::new());
        }
        Ok(observer)
    }

    /// Capsules of the checked members at the node positions `nodes`.
    fn capsules(&self, nodes: &[[f64; 3]]) -> Vec<Capsule> {
        self.members.iter().map(|t| (nodes[t.a], nodes[t.b], t.radius_m)).collect()
    }

    /// The clearances at one configuration, with this observer's exclusions.
    pub fn measure(&self, nodes: &[[f64; 3]]) -> Vec<PairClearance> {
        let excluded = &self.excluded;
        clearances(&self.capsules(nodes), self.settings.margin_m, |i, j| excluded.contains(&(i, j)))
    }

    fn pair_names(&self, i: usize, j: usize) -> [String; 2] {
        [self.members[i].name.clone(), self.members[j].name.clone()]
    }

    fn pair_kinds(&self, i: usize, j: usize) -> [String; 2] {
        [self.members[i].kind.to_string(), self.members[j].kind.to_string()]
    }

    pub fn report(&self) -> InterferenceReport {
        let mut violations = Vec::new();
        let mut closest: Option<(&(usize, usize), &PairStats)> = None;
        for (pair, st) in &self.stats {
            violations.extend(st.violations.iter().cloned());
            if let Some((first, last)) = st.open {
                violations.push(self.violation(*pair, first, last, st.open_min));
            }
            if closest.is_none_or(|(_, c)| st.min_clearance_m < c.min_clearance_m) {
                closest = Some((pair, st));
            }
        }
        violations.sort_by(|a, b| (a.first_tick, &a.pair).cmp(&(b.first_tick, &b.pair)));
        InterferenceReport {
            min_clearance_m: closest.map(|(_, st)| st.min_clearance_m),
            closest_pair: closest.map(|((i, j), _)| self.pair_names(*i, *j)),
            closest_points: closest.map(|(_, st)| st.points_at_min),
            tick_of_min: closest.map(|(_, st)| st.tick_of_min),
            enabled: self.settings.enabled,
            tendons: self.settings.tendons,
            members_checked: self.members.len(),
            pairs_checked: self.pairs_checked,
            ticks_checked: self.ticks,
            threshold_m: self.settings.threshold_m,
            margin_m: self.settings.margin_m,
            informative: self.settings.informative,
            passed: self.settings.informative || violations.is_empty(),
            violations,
            pairs: self
                .stats
                .iter()
                .map(|((i, j), st)| PairClearanceReport {
                    pair: self.pair_names(*i, *j),
                    kinds: self.pair_kinds(*i, *j),
                    min_clearance_m: st.min_clearance_m,
                    tick_of_min: st.tick_of_min,
                    closest_points: st.points_at_min,
                })
                .collect(),
        }
    }

    fn violation(
        &self,
        (i, j): (usize, usize),
        first: u64,
        last: u64,
        min: (f64, u64, [[f64; 3]; 2]),
    ) -> InterferenceViolation {
        InterferenceViolation {
            pair: self.pair_names(i, j),
            kinds: self.pair_kinds(i, j),
            first_tick: first,
            last_tick: last,
            min_clearance_m: min.0,
            tick_of_min: min.1,
            closest_points: min.2,
        }
    }
}

impl Observer for Interference {
    fn tick(&mut self, t: &Tick, notes: &mut Vec<Note>) {
        if self.settings.enabled {
            self.check(t.snapshot.tick, &t.snapshot.nodes, notes);
        }
    }

    /// The smallest clearance at the settled state, and whether it stays above the threshold.
    fn settle_point(&mut self, p: &SettlePoint, point: &mut PointReport, _notes: &mut Vec<Note>) {
        if !self.settings.enabled {
            return;
        }
        let c = self.measure(&p.snapshot.nodes).iter().map(|m| m.clearance_m).reduce(f64::min);
        point.min_clearance_m = c;
        point.interference_free = Some(c.is_none_or(|c| c >= self.settings.threshold_m));
    }

    fn finish(&mut self, report: &mut ScenarioReport) {
        report.interference = Some(self.report());
    }
}

impl Interference {
    /// Measures the members at `nodes` (tick `tick`) and keeps each pair's smallest clearance
    /// and the intervals below the threshold.
    fn check(&mut self, tick: u64, nodes: &[[f64; 3]], notes: &mut Vec<Note>) {
        self.ticks += 1;
        let measured = self.measure(nodes);
        if let Some(c) = measured.iter().map(|p| p.clearance_m).reduce(f64::min) {
            notes.push(Note::Scalar(MIN_CLEARANCE_SERIES, c));
        }
        let threshold = self.settings.threshold_m;
        let mut below = std::collections::BTreeSet::new();
        for p in &measured {
            let st = self.stats.entry((p.i, p.j)).or_insert(PairStats {
                min_clearance_m: f64::INFINITY,
                tick_of_min: tick,
                points_at_min: p.points,
                open: None,
                violations: Vec::new(),
                open_min: (f64::INFINITY, tick, p.points),
            });
            if p.clearance_m < st.min_clearance_m {
                st.min_clearance_m = p.clearance_m;
                st.tick_of_min = tick;
                st.points_at_min = p.points;
            }
            if p.clearance_m < threshold {
                below.insert((p.i, p.j));
                match &mut st.open {
                    Some(iv) => iv.1 = tick,
                    None => {
                        st.open = Some((tick, tick));
                        st.open_min = (f64::INFINITY, tick, p.points);
                        let (a, b) = (&self.members[p.i], &self.members[p.j]);
                        notes.push(Note::Event(format!(
                            "interference: {} '{}' / {} '{}' clearance {:.3e} m",
                            a.kind, a.name, b.kind, b.name, p.clearance_m
                        )));
                    }
                }
                if p.clearance_m < st.open_min.0 {
                    st.open_min = (p.clearance_m, tick, p.points);
                }
            }
        }
        // Close the intervals of pairs that are clear again.
        let to_close: Vec<(usize, usize)> =
            self.stats.iter().filter(|(k, st)| st.open.is_some() && !below.contains(*k)).map(|(k, _)| *k).collect();
        for k in to_close {
            let st = &self.stats[&k];
            let (first, last) = st.open.expect("open");
            let v = self.violation(k, first, last, st.open_min);
            let st = self.stats.get_mut(&k).expect("present");
            st.violations.push(v);
            st.open = None;
        }
    }
}
