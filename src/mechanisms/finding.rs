//! [`Finding`]: one printed equation or claim of a paper checked against the testbed's
//! derivation. Plain data, so that the papers' analytic models can build their catalogues
//! without depending on the simulation.
//!
//! Each paper's catalogue is a table of [`EquationGroup`]s, one function per group of
//! equations; [`group`] finds the group that prints a label and [`check_equation`] runs it alone.

/// A printed equation checked against the testbed's derivation.
#[derive(Clone, Debug, PartialEq)]
pub struct Finding {
    pub equation: String,
    pub claim: String,
    pub measured: String,
    pub holds: bool,
}

/// A [`Finding`] for `equation` (as the paper numbers it), `claim` (what the paper says),
/// `measured` (what the check found) and whether the claim `holds`.
pub fn finding(equation: &str, claim: &str, measured: String, holds: bool) -> Finding {
    Finding { equation: equation.to_string(), claim: claim.to_string(), measured, holds }
}

/// One group of a paper's equations, checked together by one function: `check` returns the
/// findings labelled `equations`, in that order. `C` is what every group of the paper receives:
/// its parameters, or a context of them with the samples the groups share.
pub struct EquationGroup<C: 'static> {
    /// The [`Finding::equation`] labels that `check` returns, in order, as printed
    /// (for example `["Eq. 41", "Eq. 42", "Eq. 40, 48, 50-51"]`).
    pub equations: &'static [&'static str],
    pub check: fn(&C) -> Vec<Finding>,
}

/// The group of `groups` that prints the finding labelled `equation`, exactly as the findings
/// print it (for example `"Eq. 23-25"`, `"Sec. 6.1 claim"`).
pub fn group<'a, C>(groups: &'a [EquationGroup<C>], equation: &str) -> Option<&'a EquationGroup<C>> {
    groups.iter().find(|g| g.equations.contains(&equation))
}

/// The finding labelled `equation`, computed by running its group alone.
pub fn check_equation<C>(groups: &[EquationGroup<C>], context: &C, equation: &str) -> Option<Finding> {
    (group(groups, equation)?.check)(context).into_iter().find(|f| f.equation == equation)
}

/// Every group's findings, in the table's order.
pub fn check_all<C>(groups: &[EquationGroup<C>], context: &C) -> Vec<Finding> {
    groups.iter().flat_map(|g| (g.check)(context)).collect()
}

/// Test helpers for the papers' catalogues.
#[cfg(test)]
pub(crate) mod testing {
    /// The number printed right after `prefix` in `text` (for example `3.13e-1`; a full stop
    /// after it ends the sentence).
    pub(crate) fn number_after(text: &str, prefix: &str) -> f64 {
        let start = text.find(prefix).unwrap_or_else(|| panic!("no '{prefix}' in: {text}")) + prefix.len();
        let rest = &text[start..];
        let end = rest.find(|c: char| !(c.is_ascii_digit() || "+-.e".contains(c))).unwrap_or(rest.len());
        let number = rest[..end].trim_end_matches('.');
        number.parse().unwrap_or_else(|e| panic!("'{number}' after '{prefix}': {e}"))
    }
}

#[cfg(test)]
mod tests {
    use super::testing::*;
    use super::*;
    use crate::mechanisms::{furet2018, ji2014, manriquez2019, mohr2011};

    /// Asserts that each group returns exactly the labels its table entry declares (so that
    /// [`group`] finds every printed finding) and that no label is declared twice.
    fn assert_labels_match<C>(groups: &[EquationGroup<C>], context: &C) {
        let mut seen = std::collections::BTreeSet::new();
        for g in groups {
            let printed: Vec<String> = (g.check)(context).into_iter().map(|f| f.equation).collect();
            assert_eq!(printed, g.equations, "labels of the group {:?}", g.equations);
            for e in g.equations {
                assert!(seen.insert(*e), "label {e} declared twice");
            }
        }
    }

    #[test]
    fn every_papers_groups_print_the_labels_of_their_table_entries() {
        let ji = ji2014::findings::Samples::new(&ji2014::analytic::Params::PAPER_WORKSPACE);
        assert_labels_match(ji2014::findings::EQUATION_GROUPS, &ji);
        let mohr = mohr2011::findings::Samples::new(&mohr2011::analytic::Params::PAPER);
        assert_labels_match(mohr2011::findings::EQUATION_GROUPS, &mohr);
        assert_labels_match(furet2018::findings::EQUATION_GROUPS, &furet2018::analytic::Params::PAPER);
        assert_labels_match(manriquez2019::findings::EQUATION_GROUPS, &manriquez2019::analytic::Params::PAPER);
    }

    #[test]
    fn a_group_is_found_by_any_label_it_prints_and_runs_alone() {
        fn two(_: &()) -> Vec<Finding> {
            vec![finding("Eq. 1", "a", "x = 1.5e-3. y".into(), true), finding("Eq. 2-3", "b", String::new(), false)]
        }
        fn one(_: &()) -> Vec<Finding> {
            vec![finding("Fig. 4", "c", String::new(), true)]
        }
        let table = [
            EquationGroup { equations: &["Eq. 1", "Eq. 2-3"], check: two },
            EquationGroup { equations: &["Fig. 4"], check: one },
        ];
        assert_eq!(group(&table, "Eq. 2-3").map(|g| g.equations), Some(&["Eq. 1", "Eq. 2-3"][..]));
        assert!(group(&table, "Eq. 2").is_none(), "labels match exactly as printed");
        assert!(!check_equation(&table, &(), "Eq. 2-3").unwrap().holds);
        assert_eq!(number_after(&check_equation(&table, &(), "Eq. 1").unwrap().measured, "x = "), 1.5e-3);
        assert_eq!(check_all(&table, &()).len(), 3);
        assert_labels_match(&table, &());
    }
}
