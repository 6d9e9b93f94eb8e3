//! Divergence is detected and reported with what diverged and when.

use tensegrity_testbed::settings::SimSettings;
use tensegrity_testbed::sim::{SimError, Simulation};
use tensegrity_testbed::structure::{BodyKind, Inertia, Structure};

/// An unsupported body under gravity leaves a 10 m box after about sqrt(2 * 10 / 9.81) = 1.43 s;
/// the simulator stops with a divergence naming the node, within one step of that time.
#[test]
fn a_body_leaving_the_bounding_box_is_reported_as_divergence() {
    let mut s = Structure { gravity: [0.0, 0.0, -9.81], ..Default::default() };
    let b =
        s.add_body("falling", BodyKind::Free, Some(Inertia { mass_kg: 1.0, com: [0.0; 3], principal_kg_m2: [0.1; 3] }));
    s.add_node("P", b, [0.0; 3]);
    let settings = SimSettings { dt_s: 0.01, bounding_box_m: 10.0, ..Default::default() };
    let mut sim = Simulation::new(&s, &settings).unwrap();
    let err = loop {
        if let Err(e) = sim.step() {
            break e;
        }
        assert!(sim.tick() < 1000, "never diverged");
    };
    match err {
        SimError::Diverged { tick, time_s, what } => {
            assert!(what.contains("node 'P' left the bounding box"), "{what}");
            let expected = (2.0 * 10.0 / 9.81f64).sqrt();
            assert!(
                (time_s - expected).abs() <= 0.02,
                "diverged at {time_s} s (tick {tick}), expected {expected:.3} s"
            );
        }
        other => panic!("expected divergence, got {other:?}"),
    }
}

/// A spring of zero free length between the ground and a free body pulls it to the anchor:
/// the explicit force law is exact at rest, so the settled position error is at round-off.
#[test]
fn a_free_body_on_a_zero_length_spring_settles_on_the_anchor() {
    use tensegrity_testbed::structure::Member;
    let mut s = Structure::default();
    let g = s.add_body("ground", BodyKind::Fixed, None);
    let b = s.add_body(
        "mass",
        BodyKind::Free,
        Some(Inertia { mass_kg: 1.0, com: [0.3, 0.2, 0.0], principal_kg_m2: [0.1; 3] }),
    );
    let a = s.add_node("anchor", g, [0.0; 3]);
    let p = s.add_node("P", b, [0.3, 0.2, 0.0]);
    s.members.push(Member::spring("k", [a, p], 100.0, 0.0, 1e-3));
    let settings = SimSettings { dt_s: 0.01, body_damping_per_s: 10.0, ..Default::default() };
    let mut sim = Simulation::new(&s, &settings).unwrap();
    for _ in 0..5000 {
        sim.step().unwrap();
    }
    let pos = sim.node_position(p);
    let err = (pos[0].powi(2) + pos[1].powi(2) + pos[2].powi(2)).sqrt();
    assert!(err < 1e-12, "settled {err:e} m from the anchor");
    let f = sim.member_forces();
    let r = f.residual.expect("member_forces computes the residual");
    assert!(r.max_force_n < 1e-9, "residual {:e} N", r.max_force_n);
}

/// An absurdly stiff spring (1e12 N/m on 1 kg, explicit, dt = 0.01 s) blows up: the energy
/// check stops the run within a few ticks and says so.
#[test]
fn an_absurd_stiffness_is_caught_by_the_energy_check_within_a_few_ticks() {
    use tensegrity_testbed::structure::Member;
    let mut s = Structure::default();
    let g = s.add_body("ground", BodyKind::Fixed, None);
    let b = s.add_body(
        "bob",
        BodyKind::Free,
        Some(Inertia { mass_kg: 1.0, com: [1.0, 0.0, 0.0], principal_kg_m2: [0.1; 3] }),
    );
    let a = s.add_node("A", g, [0.0; 3]);
    let p = s.add_node("P", b, [1.0, 0.0, 0.0]);
    s.members.push(Member::spring("stiff", [a, p], 1e12, 0.5, 1e-3));
    let mut sim = Simulation::new(&s, &SimSettings { dt_s: 0.01, ..Default::default() }).unwrap();
    let err = (0..100).find_map(|_| sim.step().err()).expect("diverges");
    match err {
        SimError::Diverged { tick, what, .. } => {
            assert!(tick <= 5, "caught at tick {tick}");
            assert!(what.contains("kinetic energy") || what.contains("not finite"), "{what}");
        }
        other => panic!("{other:?}"),
    }
}

/// A loop-closing joint torn open by a load it cannot carry within one step (1e9 N on a
/// 1 kg body held by an impulse joint, across the arm it hangs from) is caught by the joint-gap check. The joint joins a
/// plain body to a multibody link (as mohr2011's end-effector joins its legs): rapier's
/// velocity-level solver alone holds it; the projection closes only loops inside a multibody
/// and joints among plain bodies.
#[test]
fn a_joint_that_comes_apart_is_reported_with_its_gap() {
    use tensegrity_testbed::structure::{CableLaw, ExternalLoad, Joint, JointKind, Member};
    let mut s = Structure::default();
    let g = s.add_body("ground", BodyKind::Fixed, None);
    let arm = s.add_body(
        "arm",
        BodyKind::Free,
        Some(Inertia { mass_kg: 1.0, com: [0.5, 0.0, 0.0], principal_kg_m2: [0.1; 3] }),
    );
    let b = s.add_body(
        "bob",
        BodyKind::Free,
        Some(Inertia { mass_kg: 1.0, com: [1.0, 0.0, 0.0], principal_kg_m2: [0.1; 3] }),
    );
    let o = s.add_node("O", g, [0.0; 3]);
    let a = s.add_node("A", arm, [1.0, 0.0, 0.0]);
    let c = s.add_node("C", g, [1.0, 1.0, 0.0]);
    let p = s.add_node("P", b, [1.0, 0.0, 0.0]);
    // The cable keeps the bob a plain body, so the joint at A is an impulse (loop) joint.
    s.members.push(Member::cable("c", vec![c, p], CableLaw::Inextensible, 2.0, 1e-3));
    s.joints.push(Joint {
        name: "hinge".into(),
        kind: JointKind::Revolute { axis: [0.0, 0.0, 1.0] },
        parent: g,
        child: arm,
        anchor: o,
        initial_coordinate: 0.0,
        torsion_spring: None,
        damping: 0.0,
    });
    s.joints.push(Joint {
        name: "pivot".into(),
        kind: JointKind::Spherical,
        parent: arm,
        child: b,
        anchor: a,
        initial_coordinate: 0.0,
        torsion_spring: None,
        damping: 0.0,
    });
    s.loads.push(ExternalLoad { body: b, force_n: [0.0, 1e9, 0.0] });
    let settings = SimSettings { dt_s: 0.01, bounding_box_m: 1e12, max_kinetic_energy_j: 1e30, ..Default::default() };
    let mut sim = Simulation::new(&s, &settings).unwrap();
    let err = (0..100).find_map(|_| sim.step().err()).expect("diverges");
    match err {
        SimError::Diverged { tick, what, .. } => {
            assert!(tick <= 10, "caught at tick {tick}");
            assert!(what.contains("joint 'pivot' came apart"), "{what}");
        }
        other => panic!("{other:?}"),
    }
}
