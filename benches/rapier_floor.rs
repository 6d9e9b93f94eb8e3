//! `cargo bench --bench rapier_floor`: the cost of one rapier step for the smallest world the
//! testbed could build for ji2014 (one body on one revolute joint, one explicit spring force),
//! with the joint as a multibody link (what the testbed uses: exact joints) and as an impulse
//! joint. It bounds what any settling strategy can reach per step (BENCHMARKS.md, issue 11).
//! Each at rapier's default substeps (four) and at one, the testbed's default (`[sim]
//! substeps`): the floor of the testbed's own physical step on a hinge (issue 64).

use rapier3d_f64::prelude::*;

/// Steps per measurement, and measurements whose median is printed.
const STEPS: usize = 100_000;
const REPEATS: usize = 5;
/// Time step [s] and spring stiffness [N/m] (ji2014's grid settings).
const DT_S: f64 = 0.15;
const STIFFNESS_N_PER_M: f64 = 200.0;

fn us_per_step(multibody: bool, substeps: usize) -> f64 {
    let mut bodies = RigidBodySet::new();
    let mut colliders = ColliderSet::new();
    let mut impulse_joints = ImpulseJointSet::new();
    let mut multibody_joints = MultibodyJointSet::new();
    let ground = bodies.insert(RigidBodyBuilder::fixed());
    let body =
        bodies.insert(RigidBodyBuilder::dynamic().can_sleep(false).additional_mass_properties(MassProperties::new(
            Vector::new(0.5, 0.0, 0.0),
            1.0,
            Vector::new(0.1, 0.1, 0.33),
        )));
    let anchor = Vector::new(0.2, 0.0, 0.0);
    let joint = RevoluteJointBuilder::new(Vector::Z).local_anchor1(anchor).local_anchor2(anchor);
    if multibody {
        multibody_joints.insert(ground, body, joint, true);
    } else {
        impulse_joints.insert(ground, body, joint, true);
    }
    let mut pipeline = PhysicsPipeline::new();
    let params = IntegrationParameters { dt: DT_S, num_solver_iterations: substeps, ..Default::default() };
    let (mut islands, mut broad, mut narrow) = (IslandManager::new(), BroadPhaseBvh::new(), NarrowPhase::new());
    let (mut soft, mut ccd) = (SoftBodySet::new(), CCDSolver::new());
    let spring_anchor = Vector::new(-1.0, -1.7, 0.0);
    let start = std::time::Instant::now();
    for _ in 0..STEPS {
        let p = bodies[body].position().transform_point(Vector::new(1.0, 0.3, 0.0));
        let rb = &mut bodies[body];
        rb.reset_forces(true);
        rb.reset_torques(true);
        rb.add_force_at_point((spring_anchor - p) * STIFFNESS_N_PER_M, p, true);
        pipeline.step(
            Vector::ZERO,
            &params,
            &mut islands,
            &mut broad,
            &mut narrow,
            &mut bodies,
            &mut colliders,
            &mut impulse_joints,
            &mut multibody_joints,
            &mut soft,
            &mut ccd,
            &(),
            &(),
        );
    }
    start.elapsed().as_secs_f64() * 1e6 / STEPS as f64
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    for substeps in [IntegrationParameters::default().num_solver_iterations, 1] {
        for (label, multibody) in [("multibody revolute", true), ("impulse revolute", false)] {
            let m = median((0..REPEATS).map(|_| us_per_step(multibody, substeps)).collect());
            println!("{label}, {substeps} substep(s): {m:.2} us per rapier step (median of {REPEATS} x {STEPS} steps)");
        }
    }
}
