//! A command jump of joints locked off the multibody tree (the actuated joints of a long chain
//! cut into plain bodies, `build::LOOPED_MULTIBODY_MAX_LINKS`) taken in one stretch when the
//! closure's own convergence shows that this is safe.
//!
//! A jump from one command to another is a path in the commands; the projection
//! (`projection.rs`) must land on the configuration at the end of that path, on the assembly
//! mode the structure started on. By default the path is cut into increments of at most
//! `MAX_CLOSED_LOOP_INCREMENT` (`mod.rs`), each projected from the last. Gauss-Newton started at
//! the configuration before the jump converges to the path's end directly when that start lies
//! well inside its region of convergence, and the contraction of the first step measures how
//! well: a Newton step from x0 shrinks the gap by about h0 / 2, where h0 = omega |dx0| is the
//! Kantorovich quantity of the start (the affine covariant Newton theory of Deuflhard, *Newton
//! Methods for Nonlinear Problems*, 2004, Ch. 2 and the step-size control of continuation in
//! Sec. 5.1). The jump is taken at once when that first contraction is at most
//! [`MAX_FIRST_CONTRACTION`] and the projection closes every row to round-off; otherwise the
//! bodies go back and the increments run, starting from the Jacobian the attempt formed at the
//! start.

use super::data::Data;
use super::model::Model;
use super::projection::{Projection, GAP_TOLERANCE_FRACTION};

/// A jump is taken at once only if the first Gauss-Newton step of its projection left at most
/// this fraction of the gap that the jump opened: a quarter, Deuflhard's bound for a
/// continuation step's corrector (h0 at most 1/2, inside the Kantorovich ball in which the
/// solution is unique). Measured on furet2018 X chains commanded 0.05 rad from their start,
/// their bodies moved along the group's tree (`group_tree.rs`): 1.1e-2 at 3 modules, 7.2e-3 at
/// 5 and 4.9e-3 from 10 to 100 (each body moved by its own twist instead: 0.16 at 5, 0.44 at
/// 10 and 1.0 at 15). A 0.35 rad jump of 5 modules takes the increments.
const MAX_FIRST_CONTRACTION: f64 = 0.25;

impl Projection {
    /// Moves the actuated joints locked off the tree (`locks`: joint, locked coordinate now,
    /// command) to their commands in one stretch, followed by the projection to round-off.
    /// Returns false, with every body back where it was, when the first contraction or the
    /// closure says the stretch was too long.
    pub(super) fn jump_locked_commands_at_once(
        &mut self,
        m: &Model,
        d: &mut Data,
        locks: &[(usize, f64, f64)],
    ) -> bool {
        let before = d.projected_states(m);
        for &(j, _, command) in locks {
            d.lock_joint_at(m, j, command);
        }
        let p = self.project_groups_with(m, d, GAP_TOLERANCE_FRACTION, MAX_FIRST_CONTRACTION, true);
        let closed = p.left <= GAP_TOLERANCE_FRACTION * m.length_scale_m;
        if closed && p.first_contraction <= MAX_FIRST_CONTRACTION {
            return true;
        }
        for &(j, from, _) in locks {
            d.lock_joint_at(m, j, from);
        }
        d.restore_projected_states(m, before);
        false
    }
}
