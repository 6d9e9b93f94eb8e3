//! The names a file defines, in three namespaces: the symbols expressions read (parameters,
//! actuator symbols, quantities, energy coordinates), the members (struts, springs, cables and
//! the members of groups, generated names too) and the joints. A name is never empty, never a
//! word the expressions already give a meaning (a built-in constant or function, time `t`), and
//! never defined twice in its namespace, whatever the two kinds: the error names both places.
//! A symbol is also an identifier, so that it cannot spell a node coordinate (`B1.x`) or a
//! member's force (`k.force`); a member and a joint may share a name with a symbol (`k.force`
//! and `k` do not meet: a spring K1 of stiffness K1 is fine).

use super::error::{Ctx, ScenarioError};
use super::raw::RawScenario;
use super::structure::group_members;
use crate::file_model::expr::reserved_meaning;
use toml::Spanned;

/// The names defined so far: each with what it names and where (a byte offset).
struct Names<'a> {
    ctx: &'a Ctx<'a>,
    taken: Vec<(String, String, usize)>,
}

impl Names<'_> {
    /// Defines `name` as `what`; an error when it is empty, reserved or taken.
    fn define(&mut self, name: &Spanned<String>, what: &str) -> Result<(), ScenarioError> {
        let n = name.get_ref();
        if n.trim().is_empty() {
            return Err(self.ctx.err(name, format!("a {what} needs a name, got '{n}'")));
        }
        if let Some(meaning) = reserved_meaning(n) {
            return Err(self.ctx.err(name, format!("{what} '{n}' is {meaning}: give it another name")));
        }
        if let Some((_, other, at)) = self.taken.iter().find(|(t, ..)| t == n) {
            let place = self.ctx.err_at(*at, String::new());
            return Err(self.ctx.err(
                name,
                format!(
                    "duplicate name '{n}': this {what} and the {other} at {}:{} (every name is defined once)",
                    place.line, place.col
                ),
            ));
        }
        self.taken.push((n.clone(), what.to_string(), name.span().start));
        Ok(())
    }

    /// Defines a name that expressions read as a symbol: also an identifier.
    fn symbol(&mut self, name: &Spanned<String>, what: &str) -> Result<(), ScenarioError> {
        let n = name.get_ref();
        let mut chars = n.chars();
        let first_ok = chars.next().is_some_and(|c| c.is_ascii_alphabetic() || c == '_');
        let identifier = first_ok && chars.all(|c| c.is_ascii_alphanumeric() || c == '_');
        // An empty name is not refused here.
        if !(n.is_empty() || identifier) {
            return Err(self
                .ctx
                .err(name, format!("{what} '{n}' must be an identifier (letters, digits and _, not first a digit)")));
        }
        self.define(name, what)
    }
}

/// Every name the file defines, checked in file order of the sections.
pub(super) fn names(ctx: &Ctx, raw: &RawScenario) -> Result<(), ScenarioError> {
    let mut symbols = Names { ctx, taken: Vec::new() };
    for k in raw.params.keys() {
        symbols.symbol(k, "parameter")?;
    }
    if let Some(st) = &raw.structure {
        let s = st.get_ref();
        for a in &s.actuators {
            symbols.symbol(&a.symbol, "actuator symbol")?;
        }
        let mut members = Names { ctx, taken: Vec::new() };
        for (list, what) in [(&s.struts, "strut"), (&s.springs, "spring"), (&s.cables, "cable")] {
            for m in list {
                members.define(&m.name, what)?;
            }
        }
        let groups = [(&s.strut_groups, "strut"), (&s.spring_groups, "spring"), (&s.cable_groups, "cable")];
        for (list, what) in groups {
            for g in list {
                for m in group_members(ctx, g)? {
                    members.define(&m.name, &format!("{what} of group '{}'", g.name.get_ref()))?;
                }
            }
        }
        let mut joints = Names { ctx, taken: Vec::new() };
        for j in &s.joints {
            joints.define(&j.name, "joint")?;
        }
    }
    for q in &raw.quantities {
        symbols.symbol(&q.name, "quantity")?;
    }
    for c in raw.energy.iter().flat_map(|e| &e.coordinates) {
        symbols.symbol(&c.name, "energy coordinate")?;
    }
    Ok(())
}
