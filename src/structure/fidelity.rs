//! A paper's idealizations relaxed: the structure a model assumes (rigid struts, inextensible
//! and massless cables) rewritten into the one a prototype would be, with the physical data the
//! file states (`[[fidelity]]`, `scenario/fidelity.rs`). Each rewrite goes through the members
//! and point masses the simulator already has (`lumped.rs`), so a relaxed structure settles,
//! moves and is observed as any other. What each relaxation costs a paper's model is measured
//! by `study/attribution.rs`.

use super::lumped::{self, EndShare, Lumping};
use super::{ActuatorTarget, CableLaw, Law, Member, MemberId, Structure};

/// Actuator commands by symbol (m or rad), as a mechanism gives them.
pub type Commands = std::collections::BTreeMap<String, f64>;

/// An idealization a paper's model makes, which a relaxation undoes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Assumption {
    /// No gravity (a planar mechanism taken to lie in a horizontal plane): relaxed to the
    /// gravity a prototype feels, on every body's mass (first, so that a heavy cable's end
    /// loads weigh with it).
    NoGravity,
    /// Cables that never stretch: relaxed to elastic cables of axial stiffness EA / L0.
    InextensibleCables,
    /// Struts that never deform: relaxed to elastic bars (`lumped::make_strut_elastic`).
    RigidStruts,
    /// Cables without mass: relaxed to beads on elastic segments (`lumped::hang_beads`).
    MasslessCables,
    /// A model choice at its ideal value (an actuator's infinite stiffness, a joint without
    /// damping): relaxed to the values the file states for its parameters, the scenario read
    /// again with them as `--set` would set them.
    ParameterValues,
}

impl Assumption {
    /// Every assumption by the words a file names it with, in the order relaxations are
    /// applied together (a cable is made elastic before it is hung with beads).
    pub const ALL: [(Assumption, &'static str); 5] = [
        (Assumption::NoGravity, "no gravity"),
        (Assumption::InextensibleCables, "inextensible cables"),
        (Assumption::RigidStruts, "rigid struts"),
        (Assumption::MasslessCables, "massless cables"),
        (Assumption::ParameterValues, "parameter values"),
    ];

    /// The words a file and a report use.
    pub fn label(self) -> &'static str {
        Self::ALL.iter().find(|(a, _)| *a == self).map_or("", |(_, l)| l)
    }

    /// The assumption a file names, if any.
    pub fn from_label(label: &str) -> Option<Assumption> {
        Self::ALL.iter().find(|(_, l)| *l == label).map(|(a, _)| *a)
    }

    /// Whether the assumption holds for `m` in the ideal structure (what it may relax).
    fn holds_for(self, m: &Member) -> bool {
        match self {
            Assumption::InextensibleCables => matches!(m.law, Law::Cable { law: CableLaw::Inextensible, .. }),
            Assumption::RigidStruts => m.law == Law::Strut,
            Assumption::MasslessCables => matches!(m.law, Law::Cable { .. }),
            Assumption::NoGravity | Assumption::ParameterValues => false,
        }
    }
}

/// An assumption is written as its words (`"inextensible cables"`).
impl serde::Serialize for Assumption {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        serializer.serialize_str(self.label())
    }
}

/// One idealization relaxed, with its physical data.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Relaxation {
    /// The name a report gives its share.
    pub name: String,
    pub assumption: Assumption,
    /// The members it relaxes by name (empty: every member the assumption holds for).
    pub members: Vec<String>,
    /// The axial stiffness E A \[N\] (elastic struts and elastic cables).
    pub ea_n: Option<f64>,
    /// The linear density \[kg/m\]: a heavy cable's (per unstretched metre), an elastic strut's
    /// (its mass rho L in place of its body's).
    pub density_kg_per_m: Option<f64>,
    /// A heavy cable's segment count.
    pub segments: usize,
    /// The gravity a prototype feels, world frame \[m/s^2\] ("no gravity" relaxed).
    pub gravity_m_per_s2: Option<[f64; 3]>,
    /// The parameters' values ("parameter values" relaxed), by name.
    pub params: std::collections::BTreeMap<String, f64>,
}

/// Relaxation `r` of `list` with the relaxations it is measured on top of, as indices into
/// `list` in order: a heavy cable's "inextensible cables" (a heavy cable is elastic segments)
/// and "no gravity" (its mass weighs only under gravity).
pub fn with_base(list: &[Relaxation], r: usize) -> Vec<usize> {
    let base = [Assumption::NoGravity, Assumption::InextensibleCables];
    let under = |o: &Relaxation| list[r].assumption == Assumption::MasslessCables && base.contains(&o.assumption);
    (0..list.len()).filter(|&i| i == r || under(&list[i])).collect()
}

/// Why a structure cannot take a relaxation; the message names the member and says why.
#[derive(Debug, thiserror::Error, PartialEq)]
#[error("{0}")]
pub struct FidelityError(pub String);

/// The members of `s` that `r` relaxes: those it names (each must be one the assumption holds
/// for) or every member the assumption holds for (none where it holds for none: a parameter
/// such as a built-in mechanism's elastic cable stiffness may have relaxed it already, and the
/// report then lists no member for it).
pub fn members_of(s: &Structure, r: &Relaxation) -> Result<Vec<MemberId>, FidelityError> {
    let what = r.assumption.label();
    if r.members.is_empty() {
        return Ok((0..s.members.len()).filter(|&i| r.assumption.holds_for(&s.members[i])).collect());
    }
    r.members
        .iter()
        .map(|name| {
            let i = s
                .member_id(name)
                .ok_or_else(|| FidelityError(format!("'{}': the structure has no member '{name}'", r.name)))?;
            if !r.assumption.holds_for(&s.members[i]) {
                let kind = s.members[i].kind().label();
                return Err(FidelityError(format!(
                    "'{}': member '{name}' is a {kind} that is not one of the {what}",
                    r.name
                )));
            }
            Ok(i)
        })
        .collect()
}

/// `s` with `relaxations` applied together, in [`Assumption::ALL`]'s order; `commands` are the
/// actuators' commands at the point built (by symbol), which place a winch-driven cable at its
/// length before it is hung with beads (its winch then no longer drives it: a run that moves
/// the winch afterwards is refused where the file is read).
pub fn relax(s: &mut Structure, relaxations: &[&Relaxation], commands: &Commands) -> Result<(), FidelityError> {
    let mut order = relaxations.to_vec();
    order.sort_by_key(|r| r.assumption);
    let targets = order.iter().map(|r| members_of(s, r)).collect::<Result<Vec<_>, _>>()?;
    let mut lumping = Lumping::new(s);
    for (r, members) in order.iter().zip(targets) {
        if let (Assumption::NoGravity, Some(g)) = (r.assumption, r.gravity_m_per_s2) {
            s.gravity = g;
        }
        let lump = |e: lumped::LumpError| FidelityError(format!("'{}': {e}", r.name));
        for i in members {
            match r.assumption {
                Assumption::InextensibleCables => make_cable_elastic(s, i, need(r, r.ea_n, "EA")?),
                Assumption::RigidStruts => {
                    if let Some(rho) = r.density_kg_per_m {
                        set_strut_mass(s, i, rho);
                    }
                    lumped::make_strut_elastic(s, i, need(r, r.ea_n, "EA")?, None, &mut lumping).map_err(lump)?
                }
                Assumption::MasslessCables => {
                    if let Law::Cable { law: CableLaw::Inextensible, .. } = s.members[i].law {
                        let name = &s.members[i].name;
                        return Err(FidelityError(format!(
                            "'{}': cable '{name}' is inextensible, and a heavy cable is built of elastic segments: relax \"inextensible cables\" for it too (the heavy cable's share is then measured with it elastic)",
                            r.name
                        )));
                    }
                    release_winch(s, i, commands);
                    let rho = need(r, r.density_kg_per_m, "density")?;
                    lumped::hang_beads_with(s, i, (rho, r.segments), EndShare::NodeLoad, &mut lumping).map_err(lump)?
                }
                Assumption::NoGravity | Assumption::ParameterValues => {}
            }
        }
    }
    Ok(())
}

/// A relaxation's datum `value` called `key`, or the error that names it.
fn need(r: &Relaxation, value: Option<f64>, key: &str) -> Result<f64, FidelityError> {
    value.ok_or_else(|| FidelityError(format!("'{}': relaxing {} needs {key}", r.name, r.assumption.label())))
}

/// Cable `i` elastic with the axial stiffness `ea_n` over its unstretched length: EA / L0 \[N/m\].
fn make_cable_elastic(s: &mut Structure, i: MemberId, ea_n: f64) {
    if let Law::Cable { law, length_m } = &mut s.members[i].law {
        *law = CableLaw::Elastic { stiffness_n_per_m: ea_n / *length_m };
    }
}

/// Strut `i`'s body given the mass rho L of the strut as drawn.
fn set_strut_mass(s: &mut Structure, i: MemberId, rho_kg_per_m: f64) {
    let (a, b) = s.members[i].ends();
    let length = super::distance(s.nodes[a].position, s.nodes[b].position);
    if let Some(inertia) = s.bodies[s.nodes[a].body].inertia.as_mut() {
        let grown = rho_kg_per_m * length / inertia.mass_kg;
        inertia.mass_kg *= grown;
        inertia.principal_kg_m2 = inertia.principal_kg_m2.map(|m| m * grown);
    }
}

/// Cable `i`'s winch, if one drives it, set to its command and removed: the cable is built at
/// the commanded unstretched length and keeps it.
fn release_winch(s: &mut Structure, i: MemberId, commands: &Commands) {
    let Some(w) = s.actuators.iter().position(|a| a.target == ActuatorTarget::CableLength(i)) else { return };
    if let (Some(&length), Law::Cable { length_m, .. }) = (commands.get(&s.actuators[w].symbol), &mut s.members[i].law)
    {
        *length_m = length;
    }
    s.actuators.remove(w);
}

/// Whether relaxing `r` in `s` takes a cable off its winch (a heavy cable's length is built, not
/// driven): a run whose points move the winch without rebuilding is then refused.
pub fn releases_winch(s: &Structure, r: &Relaxation) -> bool {
    r.assumption == Assumption::MasslessCables
        && members_of(s, r)
            .is_ok_and(|ms| ms.iter().any(|&i| s.actuators.iter().any(|a| a.target == ActuatorTarget::CableLength(i))))
}

/// How a relaxed structure is read as the ideal one, found once per structure (a snapshot is
/// read with it at every tick): each heavy cable keeps its first segment at its own index
/// (`{name}_s1`) and is read at its last segment (`{name}_s{n}`), at the node its path ends
/// on, where a paper's model meets it; and, where any cable was hung with beads, the structure
/// with those first segments named as the ideal cables were, so that a mechanism finds them by
/// their names.
#[derive(Clone, Debug)]
pub struct IdealView {
    members: usize,
    /// (first segment, last segment) of each cable hung with two or more beads' segments.
    heavy: Vec<(MemberId, MemberId)>,
    named: Option<Structure>,
}

impl IdealView {
    /// The view of the relaxed structure `s`, in one pass over its members' names.
    pub fn of(s: &Structure) -> IdealView {
        let index: std::collections::HashMap<&str, MemberId> =
            s.members.iter().enumerate().map(|(i, m)| (m.name.as_str(), i)).collect();
        let first = |m: &Member| matches!(m.law, Law::Cable { .. }) && m.name.ends_with("_s1");
        let heavy = (0..s.members.len())
            .filter(|&i| first(&s.members[i]))
            .filter_map(|i| {
                let cable = &s.members[i].name[..s.members[i].name.len() - "_s1".len()];
                let last =
                    (2..=lumped::MAX_CABLE_SEGMENTS).map_while(|k| index.get(format!("{cable}_s{k}").as_str())).last();
                last.map(|&l| (i, l))
            })
            .collect();
        let named = s.members.iter().any(first).then(|| {
            let mut named = s.clone();
            for m in named.members.iter_mut().filter(|m| first(m)) {
                m.name.truncate(m.name.len() - "_s1".len());
            }
            named
        });
        IdealView { members: s.members.len(), heavy, named }
    }

    /// Whether this is the view of `s` (a structure of the same members).
    pub fn fits(&self, s: &Structure) -> bool {
        self.members == s.members.len()
    }

    /// The members' forces `force_n` as the ideal members carry them; None where no cable
    /// was hung with beads (they are the ideal's as they are).
    pub fn forces(&self, force_n: &[f64]) -> Option<Vec<f64>> {
        (!self.heavy.is_empty()).then(|| {
            let mut forces = force_n.to_vec();
            for &(first, last) in &self.heavy {
                forces[first] = force_n[last];
            }
            forces
        })
    }

    /// The structure a mechanism reads: `s` with its heavy cables named as the ideal's.
    pub fn structure<'a>(&'a self, s: &'a Structure) -> &'a Structure {
        self.named.as_ref().unwrap_or(s)
    }
}
