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

use super::{Made, Note, Observer, SettlePoint, Setup, Tick};
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

/// The most pairs the report lists (the closest); it counts the rest. A thousand struts with
/// their tendons have 8 million pairs within a structure-sized margin, 2 GB as a list.
pub const REPORTED_PAIRS_MAX: usize = 1000;

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

/// Clearance of every pair of capsules closer than `margin_m`, except the excluded ones, in
/// pair order.
pub fn clearances(
    capsules: &[Capsule],
    margin_m: f64,
    excluded: impl FnMut(usize, usize) -> bool,
) -> Vec<PairClearance> {
    let mut out = Vec::new();
    visit_clearances(capsules, margin_m, excluded, |p| out.push(p));
    out
}

/// Calls `visit` with the clearance of every pair of capsules closer than `margin_m`, in pair
/// order (i < j, by i then j), except those `excluded` names (asked in the same order). The
/// per-tick check folds each into its statistics as it comes, in one sequential pass: a
/// structure whose every pair lies within the margin (a thousand members and more) costs no
/// list of clearances and no lookup by hash.
pub fn visit_clearances(
    capsules: &[Capsule],
    margin_m: f64,
    mut excluded: impl FnMut(usize, usize) -> bool,
    mut visit: impl FnMut(PairClearance),
) {
    let mut narrow = |i: usize, j: usize| {
        if !excluded(i, j) {
            if let Some(p) = pair_clearance(capsules, i, j, margin_m) {
                visit(p);
            }
        }
    };
    let boxes = inflated_boxes(capsules, margin_m);
    let n = capsules.len();
    if n <= DIRECT_PAIRS_MAX_CAPSULES {
        for i in 0..n {
            for j in i + 1..n {
                if boxes[i].intersects(&boxes[j]) {
                    narrow(i, j);
                }
            }
        }
        return;
    }
    let bvh = Bvh::from_leaves(BvhBuildStrategy::Binned, &boxes);
    let mut near = Vec::new();
    for (i, bx) in boxes.iter().enumerate() {
        near.clear();
        near.extend(bvh.intersect_aabb(bx).map(|j| j as usize).filter(|&j| j > i));
        near.sort_unstable();
        for &j in &near {
            narrow(i, j);
        }
    }
}

/// Each capsule's box, inflated by its radius and half the margin: two boxes overlap when
/// the capsules may come within the margin (the broad phase).
fn inflated_boxes(capsules: &[Capsule], margin_m: f64) -> Vec<Aabb> {
    let half = 0.5 * margin_m;
    let inflated = |(a, b, r): &Capsule| {
        let (a, b) = (vec3(*a), vec3(*b));
        let pad = Vector::splat(r + half);
        Aabb::new(a.min(b) - pad, a.max(b) + pad)
    };
    capsules.iter().map(inflated).collect()
}

/// Keeps the smaller of `least` and `c` in `least`.
fn lower(least: &mut Option<f64>, c: f64) {
    *least = Some(least.map_or(c, |l| l.min(c)));
}

/// Membership in `sorted` (pairs in order) for pairs asked in increasing order: one pass.
fn member_of(sorted: &[(usize, usize)]) -> impl FnMut(usize, usize) -> bool + '_ {
    let mut at = 0;
    move |i, j| {
        while at < sorted.len() && sorted[at] < (i, j) {
            at += 1;
        }
        sorted.get(at) == Some(&(i, j))
    }
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

/// A pair's smallest clearance over the run, where it fell and the closest points there.
#[derive(Clone, Copy, Debug)]
struct PairStats {
    pair: (usize, usize),
    min_clearance_m: f64,
    tick_of_min: u64,
    points_at_min: [[f64; 3]; 2],
}

/// A violation interval still open: its first and last tick so far and its smallest
/// clearance (with the tick and the closest points there).
#[derive(Clone, Copy, Debug)]
struct OpenInterval {
    first: u64,
    last: u64,
    min: (f64, u64, [[f64; 3]; 2]),
}

/// The interference observer. Its statistics hold one small record per pair that ever came
/// within the margin, in pair order, so that a tick folds the clearances (which come in the
/// same order) into them in one sequential pass.
pub struct Interference {
    settings: InterferenceSettings,
    members: Vec<Segment>,
    /// The pairs not checked, in order.
    excluded: Vec<(usize, usize)>,
    pairs_checked: usize,
    /// Each pair's record, in pair order.
    stats: Vec<PairStats>,
    /// Violation intervals still open, by pair.
    open: BTreeMap<(usize, usize), OpenInterval>,
    /// Violation intervals closed.
    closed: Vec<((usize, usize), InterferenceViolation)>,
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
        let mut excluded: Vec<(usize, usize)> = excluded.into_iter().collect();
        excluded.sort_unstable();
        let n = members.len();
        let pairs_checked = n * n.saturating_sub(1) / 2 - excluded.iter().filter(|(i, j)| i != j).count();
        let mut observer = Interference {
            settings: settings.clone(),
            members,
            excluded,
            pairs_checked,
            stats: Vec::new(),
            open: BTreeMap::new(),
            closed: Vec::new(),
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

    fn pair_names(&self, i: usize, j: usize) -> [String; 2] {
        [self.members[i].name.clone(), self.members[j].name.clone()]
    }

    fn pair_kinds(&self, i: usize, j: usize) -> [String; 2] {
        [self.members[i].kind.to_string(), self.members[j].kind.to_string()]
    }

    pub fn report(&self) -> InterferenceReport {
        let listed = self.listed_pairs();
        // Closed and open intervals by first tick, then names, then pair (one pair's intervals
        // never share a first tick).
        let mut by_pair: Vec<((usize, usize), InterferenceViolation)> = self.closed.clone();
        by_pair.extend(self.open.iter().map(|(&pair, iv)| (pair, self.violation(pair, iv.first, iv.last, iv.min))));
        by_pair.sort_by(|(p, a), (q, b)| (a.first_tick, &a.pair, p).cmp(&(b.first_tick, &b.pair, q)));
        let violations: Vec<InterferenceViolation> = by_pair.into_iter().map(|(_, v)| v).collect();
        let closest = self.stats.iter().reduce(|c, st| if st.min_clearance_m < c.min_clearance_m { st } else { c });
        InterferenceReport {
            min_clearance_m: closest.map(|st| st.min_clearance_m),
            closest_pair: closest.map(|st| self.pair_names(st.pair.0, st.pair.1)),
            closest_points: closest.map(|st| st.points_at_min),
            tick_of_min: closest.map(|st| st.tick_of_min),
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
            pairs_within_margin: (listed.len() < self.stats.len()).then_some(self.stats.len()),
            pairs: listed
                .iter()
                .map(|st| PairClearanceReport {
                    pair: self.pair_names(st.pair.0, st.pair.1),
                    kinds: self.pair_kinds(st.pair.0, st.pair.1),
                    min_clearance_m: st.min_clearance_m,
                    tick_of_min: st.tick_of_min,
                    closest_points: st.points_at_min,
                })
                .collect(),
        }
    }

    /// The pairs the report lists, in pair order: all that came within the margin, or past
    /// `REPORTED_PAIRS_MAX`, that many, the closest (ties by pair order).
    fn listed_pairs(&self) -> Vec<&PairStats> {
        let mut listed: Vec<&PairStats> = self.stats.iter().collect();
        if listed.len() > REPORTED_PAIRS_MAX {
            let closer = |a: &&PairStats, b: &&PairStats| {
                a.min_clearance_m.total_cmp(&b.min_clearance_m).then(a.pair.cmp(&b.pair))
            };
            listed.select_nth_unstable_by(REPORTED_PAIRS_MAX, closer);
            listed.truncate(REPORTED_PAIRS_MAX);
            listed.sort_unstable_by_key(|st| st.pair);
        }
        listed
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

/// Every run checks its struts' and cables' clearances (`observers::KINDS`); an exclusion
/// naming no member stops the run from starting.
pub(super) fn make(setup: &Setup, _warnings: &mut Vec<String>) -> Made {
    Ok(Some(Box::new(Interference::new(setup.structure, setup.interference)?)))
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
        let mut c: Option<f64> = None;
        let capsules = self.capsules(&p.snapshot.nodes);
        visit_clearances(&capsules, self.settings.margin_m, member_of(&self.excluded), |m| {
            lower(&mut c, m.clearance_m);
        });
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
        let threshold = self.settings.threshold_m;
        let capsules = self.capsules(nodes);
        let (stats, open) = (&mut self.stats, &mut self.open);
        let mut least: Option<f64> = None;
        let mut opened = Vec::new();
        let mut fresh = Vec::new();
        let mut at = 0;
        visit_clearances(&capsules, self.settings.margin_m, member_of(&self.excluded), |p| {
            lower(&mut least, p.clearance_m);
            while at < stats.len() && stats[at].pair < (p.i, p.j) {
                at += 1;
            }
            let st = if stats.get(at).is_some_and(|st| st.pair == (p.i, p.j)) {
                &mut stats[at]
            } else {
                let pair = (p.i, p.j);
                fresh.push(PairStats {
                    pair,
                    min_clearance_m: f64::INFINITY,
                    tick_of_min: tick,
                    points_at_min: p.points,
                });
                fresh.last_mut().expect("just pushed")
            };
            if p.clearance_m < st.min_clearance_m {
                st.min_clearance_m = p.clearance_m;
                st.tick_of_min = tick;
                st.points_at_min = p.points;
            }
            if p.clearance_m < threshold {
                let iv = open.entry((p.i, p.j)).or_insert_with(|| {
                    opened.push(p);
                    OpenInterval { first: tick, last: tick, min: (f64::INFINITY, tick, p.points) }
                });
                iv.last = tick;
                if p.clearance_m < iv.min.0 {
                    iv.min = (p.clearance_m, tick, p.points);
                }
            }
        });
        if self.stats.is_empty() {
            fresh.shrink_to_fit();
            self.stats = fresh;
        } else if !fresh.is_empty() {
            self.stats.extend(fresh);
            self.stats.sort_by_key(|st| st.pair);
        }
        if let Some(c) = least {
            notes.push(Note::Scalar(MIN_CLEARANCE_SERIES, c));
        }
        opened.sort_by_key(|p| (p.i, p.j));
        for p in opened {
            let (a, b) = (&self.members[p.i], &self.members[p.j]);
            notes.push(Note::Event(format!(
                "interference: {} '{}' / {} '{}' clearance {:.3e} m",
                a.kind, a.name, b.kind, b.name, p.clearance_m
            )));
        }
        // Close the intervals of pairs that are clear again.
        let to_close: Vec<(usize, usize)> =
            self.open.iter().filter(|(_, iv)| iv.last != tick).map(|(k, _)| *k).collect();
        for k in to_close {
            let iv = self.open.remove(&k).expect("open");
            self.closed.push((k, self.violation(k, iv.first, iv.last, iv.min)));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A reproducible stream of numbers in [0, 1) (a linear congruential generator).
    fn uniform(seed: &mut u64) -> f64 {
        *seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (*seed >> 11) as f64 / (1u64 << 53) as f64
    }

    /// 300 capsules (past the direct test's 48) up to 0.3 m long in a 1 m cube, radius 10 mm.
    fn scattered_capsules() -> Vec<Capsule> {
        let mut seed = 7;
        let mut point = |scale: f64| [0; 3].map(|_| scale * uniform(&mut seed));
        (0..300)
            .map(|_| {
                let a = point(1.0);
                let d = point(0.3);
                (a, [a[0] + d[0], a[1] + d[1], a[2] + d[2]], 0.01)
            })
            .collect()
    }

    #[test]
    fn the_bounding_volume_hierarchy_finds_every_pair_the_direct_test_finds_in_pair_order() {
        let capsules = scattered_capsules();
        let margin_m = 0.05;
        let n = capsules.len();
        let direct: Vec<PairClearance> = (0..n)
            .flat_map(|i| (i + 1..n).map(move |j| (i, j)))
            .filter_map(|(i, j)| pair_clearance(&capsules, i, j, margin_m))
            .collect();
        let skipped = |i: usize, j: usize| (i + j).is_multiple_of(17);
        let found = clearances(&capsules, margin_m, skipped);
        let expected: Vec<PairClearance> = direct.into_iter().filter(|p| !skipped(p.i, p.j)).collect();
        assert!(expected.len() > 400, "a dense enough sample: {}", expected.len());
        assert_eq!(found, expected);
    }

    #[test]
    fn past_its_bound_the_report_lists_the_closest_pairs_in_pair_order_and_counts_them_all() {
        let members: Vec<Segment> =
            (0..60).map(|k| Segment { name: format!("m{k}"), kind: "strut", a: 0, b: 0, radius_m: 0.0 }).collect();
        let pairs: Vec<(usize, usize)> = (0..60).flat_map(|i| (i + 1..60).map(move |j| (i, j))).collect();
        assert_eq!(pairs.len(), 1770);
        // Clearance 1 m + k mm for the k-th pair in a scrambled order: the listed ones are those
        // whose k is below the bound.
        let rank = |p: usize| (p * 7919) % pairs.len();
        let stats = pairs
            .iter()
            .enumerate()
            .map(|(p, &pair)| PairStats {
                pair,
                min_clearance_m: 1.0 + 1e-3 * rank(p) as f64,
                tick_of_min: 0,
                points_at_min: [[0.0; 3]; 2],
            })
            .collect();
        let observer = Interference {
            settings: InterferenceSettings::default_on(10.0),
            members,
            excluded: Vec::new(),
            pairs_checked: pairs.len(),
            stats,
            open: BTreeMap::new(),
            closed: Vec::new(),
            ticks: 1,
        };
        let report = observer.report();
        assert_eq!(report.pairs.len(), REPORTED_PAIRS_MAX);
        assert_eq!(report.pairs_within_margin, Some(1770));
        let expected: Vec<[String; 2]> = (0..pairs.len())
            .filter(|&p| rank(p) < REPORTED_PAIRS_MAX)
            .map(|p| [format!("m{}", pairs[p].0), format!("m{}", pairs[p].1)])
            .collect();
        let listed: Vec<[String; 2]> = report.pairs.iter().map(|p| p.pair.clone()).collect();
        assert_eq!(listed, expected);
        assert_eq!(report.min_clearance_m, Some(1.0));
    }
}
