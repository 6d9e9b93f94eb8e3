//! Strut interference, every tick: struts are capsules (a segment and a radius); two capsules
//! interfere when the distance between their segments is below the sum of their radii.
//!
//! Broad phase: parry's bounding volume hierarchy over the capsules' boxes, inflated by the
//! margin, so that only nearby pairs reach the narrow phase. Narrow phase: parry's closed-form
//! segment-segment closest points; clearance = segment distance - r1 - r2 (negative: overlap).
//!
//! Pairs that meet at a joint (a shared node, or endpoints that coincide in the initial
//! configuration) always touch there and are excluded, as are pairs the scenario lists.

use super::{Note, Observer, SettlePoint, Tick};
use crate::report::{InterferenceReport, InterferenceViolation, PairClearanceReport, PointReport, ScenarioReport};
use crate::settings::InterferenceSettings;
use crate::structure::Structure;
use parry3d_f64::bounding_volume::Aabb;
use parry3d_f64::math::Vector;
use parry3d_f64::partitioning::{Bvh, BvhBuildStrategy};
use parry3d_f64::query::details::closest_points_segment_segment_with_locations_nD;
use std::collections::BTreeMap;

/// The time series of the smallest clearance at each tick (in the recording).
const MIN_CLEARANCE_SERIES: &str = "interference/min_clearance_m";

/// Endpoints closer than this fraction of the structure's size count as the same joint.
const COINCIDENT_FRACTION: f64 = 1e-9;

/// One capsule: segment ends [m] and radius [m].
pub type Capsule = ([f64; 3], [f64; 3], f64);

/// A measured pair: indices (i < j), clearance [m] and the closest points on the two axes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PairClearance {
    pub i: usize,
    pub j: usize,
    pub clearance_m: f64,
    pub points: [[f64; 3]; 2],
}

fn vec3(a: [f64; 3]) -> Vector {
    Vector::new(a[0], a[1], a[2])
}

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
    let bvh = Bvh::from_leaves(BvhBuildStrategy::Binned, &boxes);
    let mut out = Vec::new();
    for (i, j) in bvh.leaf_pairs(&bvh, |n1, n2| n1.intersects(n2)) {
        let (i, j) = (i as usize, j as usize);
        if i >= j || excluded(i, j) {
            continue;
        }
        let (a1, b1, r1) = capsules[i];
        let (a2, b2, r2) = capsules[j];
        let (a1, b1, a2, b2) = (vec3(a1), vec3(b1), vec3(a2), vec3(b2));
        let (l1, l2) = closest_points_segment_segment_with_locations_nD((&a1, &b1), (&a2, &b2));
        let s1 = parry3d_f64::shape::Segment::new(a1, b1);
        let s2 = parry3d_f64::shape::Segment::new(a2, b2);
        let (p1, p2) = (s1.point_at(&l1), s2.point_at(&l2));
        let clearance_m = (p1 - p2).length() - r1 - r2;
        if clearance_m <= margin_m {
            out.push(PairClearance { i, j, clearance_m, points: [[p1.x, p1.y, p1.z], [p2.x, p2.y, p2.z]] });
        }
    }
    out.sort_by_key(|p| (p.i, p.j));
    out
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
    names: Vec<String>,
    excluded: Vec<Vec<bool>>,
    pairs_checked: usize,
    stats: BTreeMap<(usize, usize), PairStats>,
    ticks: u64,
}

impl Interference {
    /// Sets up the pairs for `s`. Unknown strut names in `exclude` are an error.
    pub fn new(s: &Structure, settings: &InterferenceSettings) -> Result<Self, String> {
        let n = s.struts.len();
        let size = crate::structure::structure_size(s);
        let mut excluded = vec![vec![false; n]; n];
        let ends = |k: usize| [s.struts[k].a, s.struts[k].b];
        for i in 0..n {
            excluded[i][i] = true;
            for j in i + 1..n {
                let meet = ends(i).iter().any(|&p| {
                    ends(j).iter().any(|&q| {
                        p == q
                            || crate::structure::distance(s.nodes[p].position, s.nodes[q].position)
                                <= COINCIDENT_FRACTION * size
                    })
                });
                excluded[i][j] = meet;
                excluded[j][i] = meet;
            }
        }
        settings.check_strut_names(s)?;
        let id = |name: &str| s.struts.iter().position(|t| t.name == name).expect("checked above");
        for (a, b) in &settings.exclude {
            let (i, j) = (id(a), id(b));
            excluded[i][j] = true;
            excluded[j][i] = true;
        }
        let pairs_checked = (0..n).map(|i| (i + 1..n).filter(|&j| !excluded[i][j]).count()).sum();
        Ok(Interference {
            settings: settings.clone(),
            names: s.struts.iter().map(|t| t.name.clone()).collect(),
            excluded,
            pairs_checked,
            stats: BTreeMap::new(),
            ticks: 0,
        })
    }

    /// Capsules of the structure's struts at the node positions `nodes`.
    pub fn capsules(s: &Structure, nodes: &[[f64; 3]]) -> Vec<Capsule> {
        s.struts.iter().map(|t| (nodes[t.a], nodes[t.b], t.radius_m)).collect()
    }

    /// The clearances at one configuration, with this observer's exclusions.
    pub fn measure(&self, s: &Structure, nodes: &[[f64; 3]]) -> Vec<PairClearance> {
        let excluded = &self.excluded;
        clearances(&Self::capsules(s, nodes), self.settings.margin_m, |i, j| excluded[i][j])
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
            closest_pair: closest.map(|((i, j), _)| [self.names[*i].clone(), self.names[*j].clone()]),
            closest_points: closest.map(|(_, st)| st.points_at_min),
            tick_of_min: closest.map(|(_, st)| st.tick_of_min),
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
                    pair: [self.names[*i].clone(), self.names[*j].clone()],
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
            pair: [self.names[i].clone(), self.names[j].clone()],
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
        let tick = t.snapshot.tick;
        self.ticks += 1;
        let measured = self.measure(t.structure, &t.snapshot.nodes);
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
                        notes.push(Note::Event(format!(
                            "interference: {} / {} clearance {:.3e} m",
                            self.names[p.i], self.names[p.j], p.clearance_m
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

    /// The smallest clearance at the settled state, and whether it stays above the threshold.
    fn settle_point(&mut self, p: &SettlePoint, point: &mut PointReport, _notes: &mut Vec<Note>) {
        let c = self.measure(p.structure, &p.snapshot.nodes).iter().map(|m| m.clearance_m).reduce(f64::min);
        point.min_clearance_m = c;
        point.interference_free = Some(c.is_none_or(|c| c >= self.settings.threshold_m));
    }

    fn finish(&mut self, report: &mut ScenarioReport) {
        report.interference = Some(self.report());
    }
}
