//! The furet2018 family of `tensegrity bench --scale`: n Snelson X modules in series (the bird
//! neck of the paper's Fig. 1), n = 1 .. 100, each X as the built-in mechanism builds its two
//! (`mechanisms/furet2018/build.rs`: crossed bars A-C and B-D in planes twice
//! [`plane_offset_m`](crate::mechanisms::furet2018::build::ModelChoices::plane_offset_m) apart,
//! top bar D-C, revolute joints about z at A (actuated), B and C, the loop closed at D by a
//! planar pin, lateral springs A-D and B-C), X(i + 1) standing on X(i)'s top bar.
//!
//! Every X is commanded to theta = [`THETA_RAD`] through its base-joint angle
//! phi = theta + atan2(l, b cos theta) and drawn at theta + [`START_OFFSET_RAD`]; with ideal
//! actuators the chain's pose is the kinematics' alone, so the settled end point (the last
//! top-bar midpoint) is compared with the direct kinematics of n modules, Eq. 2
//! (`analytic::direct_kinematics_n`). L = 1 m, b = 2/3 m (Fig. 3-4) and the mechanism's
//! default model choices.

use super::{Case, Measure};
use crate::mechanisms::furet2018::analytic::{self, Params};
use crate::mechanisms::furet2018::build::build_chain;
use crate::mechanisms::furet2018::default_model_choices;
use crate::settings::SimSettings;
use crate::structure::Structure;

/// Module counts of the family.
pub const MODULES: [usize; 10] = [1, 2, 3, 5, 10, 15, 20, 30, 50, 100];
/// The commanded theta of every X \[rad\].
pub const THETA_RAD: f64 = 0.1;
/// The start's theta past the commanded one \[rad\].
pub const START_OFFSET_RAD: f64 = 0.05;
/// Time step [s] (the furet2018 scenarios').
const DT_S: f64 = 0.005;
/// PGS iterations of a chain kept as a multibody (the default; the furet2018 scenarios take
/// 64). The projection closes every joint of a chain after each step, so the iterations only
/// set how far rapier's step opens them first: measured on 10 X cut into plain bodies, 64
/// iterations opened them by 9.1e-4 m and 8 by 7.8e-3 m (rows scaled to metres), at the same
/// 11 steps and errors, and 8 settled in 0.7 of the time.
const MULTIBODY_PGS_ITERATIONS: usize = 8;
/// PGS iterations of a chain cut into plain bodies (more than
/// [`crate::sim::LOOPED_MULTIBODY_MAX_LINKS`] links). It is rigid at its commands and goes back
/// to its closed configuration at rest whenever rapier's step moved it less than 1e-2 of its
/// size: 2 iterations keep it there (1 does not), and settled 3 to 100 X in 0.89 to 0.92 of
/// the time of 8, at the same steps and errors (1 and 2 X, multibodies, took 1.04 and 1.06).
const CUT_PGS_ITERATIONS: usize = 2;
/// Links of one X module: its bars A-C, B-D and D-C.
const LINKS_PER_X: usize = 3;

/// n X modules drawn at `thetas` (one per module), as the built-in mechanism builds its two;
/// returns the structure and each module's top-midpoint node.
pub fn chain(p: &Params, thetas: &[f64]) -> (Structure, Vec<usize>) {
    let name = format!("furet2018 x{}", thetas.len());
    build_chain(&name, p, &default_model_choices(), &analytic::chain_nodes(p, thetas))
}

/// The n-module case: drawn at theta + [`START_OFFSET_RAD`], commanded to [`THETA_RAD`]; the
/// target is the end point of Eq. 2.
pub fn case(n: usize) -> Case {
    let p = Params::PAPER;
    let (start, ends) = chain(&p, &vec![THETA_RAD + START_OFFSET_RAD; n]);
    let (x, y) = analytic::direct_kinematics_n(&p, &vec![THETA_RAD; n]);
    Case {
        family: "furet",
        size: n,
        start,
        // The default settling: with ideal actuators the chain's pose is kinematic and the
        // position projection of the loop closures (`sim/projection.rs`) settles it (11 steps
        // at every n measured, with or without the Newton damping schedule).
        settings: SimSettings { dt_s: DT_S, pgs_iterations: pgs_iterations(n), ..Default::default() },
        commands: vec![analytic::base_joint_angle_a(&p, THETA_RAD); n],
        target: vec![(ends[n - 1], [x, y, 0.0])],
        measure: Measure::Absolute,
        spin: None,
        drive: None,
    }
}

/// The PGS iterations of an n-module chain: fewer once it is cut into plain bodies.
fn pgs_iterations(n: usize) -> usize {
    if LINKS_PER_X * n > crate::sim::LOOPED_MULTIBODY_MAX_LINKS {
        CUT_PGS_ITERATIONS
    } else {
        MULTIBODY_PGS_ITERATIONS
    }
}
