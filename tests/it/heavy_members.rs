//! Past the rigid strut and the massless cable (`structure/lumped.rs`): heavy cables built of
//! beads and elastic segments, elastic struts built of two point masses and an axial member,
//! each against an exact result.

use super::common;
use std::path::Path;
use tensegrity_testbed::run::{self, settle_first_point, RunOptions};
use tensegrity_testbed::scenario;

const BEADED: &str = "scenarios/custom/beaded_string.toml";

/// The beaded string's numbers (the shipped file's parameters): N segments, span, L0, k, rho.
const SEGMENTS: usize = 6;
const SPAN_M: f64 = 1.2;
const L0_M: f64 = 1.0;
const K_N_PER_M: f64 = 500.0;
const RHO_KG_PER_M: f64 = 0.3;

/// omega_j = 2 sqrt(T / (m a)) sin(j pi / (2 (n + 1))) of n = N - 1 beads [rad/s].
fn beaded_transverse(j: usize) -> f64 {
    let (n, tension) = (SEGMENTS as f64, K_N_PER_M * (SPAN_M - L0_M));
    let (m, a) = (RHO_KG_PER_M * L0_M / n, SPAN_M / n);
    2.0 * (tension / (m * a)).sqrt() * (j as f64 * std::f64::consts::PI / (2.0 * n)).sin()
}

/// The same with T / a replaced by a segment's stiffness N k: the axial frequencies [rad/s].
fn beaded_axial(j: usize) -> f64 {
    let n = SEGMENTS as f64;
    let m = RHO_KG_PER_M * L0_M / n;
    2.0 * (n * K_N_PER_M / m).sqrt() * (j as f64 * std::f64::consts::PI / (2.0 * n)).sin()
}

/// The non-zero modal frequencies of a scenario's settled first point, ascending, with each
/// one's mode number (from 1) [rad/s].
fn modal_frequencies(path: &str, text: &str) -> Vec<(usize, f64)> {
    let sc = scenario::parse(Path::new(path), text).expect("valid");
    let mut state = settle_first_point(&sc, None).expect("settles");
    assert!(state.settled, "{path} settles");
    let modes = state.sim.modes().expect("modes");
    modes.modes.iter().enumerate().filter(|(_, m)| !m.rigid).map(|(i, m)| (i + 1, m.omega())).collect()
}

/// n = 5 beads: the modal analysis gives each transverse frequency twice (the two planes) and
/// each axial one once, every one within 1e-9 of the closed form (measured: 1e-15 to 3e-15),
/// and nothing else: the beads' turns are left out (no rigid mode, 15 coordinates of 30).
#[test]
fn the_beaded_strings_modes_are_the_closed_form_within_1e_9() {
    let text = std::fs::read_to_string(BEADED).unwrap();
    let got = modal_frequencies(BEADED, &text);
    let n = SEGMENTS - 1;
    let mut want: Vec<f64> =
        (1..=n).flat_map(|j| [beaded_transverse(j), beaded_transverse(j), beaded_axial(j)]).collect();
    want.sort_by(f64::total_cmp);
    assert_eq!(got.len(), want.len(), "{got:?}");
    assert_eq!(got[0].0, 1, "the beads' turns are no modes");
    for ((_, g), w) in got.iter().zip(&want) {
        assert!(((g - w) / w).abs() <= 1e-9, "{g} vs {w}");
    }
}

/// Each of the five transverse modes, displaced and left to vibrate: the frequency fitted to
/// its coordinate meets the closed form within 1e-9 relative (the judged motion's own estimate
/// below it), as the shipped file does for the first.
#[test]
fn the_beaded_strings_motion_gives_every_transverse_frequency_within_1e_9() {
    let text = std::fs::read_to_string(BEADED).unwrap();
    let modal = modal_frequencies(BEADED, &text);
    for j in 1..=SEGMENTS - 1 {
        let w = beaded_transverse(j);
        let (mode, _) = *modal.iter().find(|(_, g)| ((g - w) / w).abs() <= 1e-9).expect("the mode");
        let variant = common::edited(
            BEADED,
            &[
                ("mode = 1              #", &format!("mode = {mode}              #")),
                ("mode = 1\nformula = \"w0*sin(1*pi", &format!("mode = {mode}\nformula = \"w0*sin({j}*pi")),
            ],
        );
        let sc = scenario::parse(Path::new("beaded.toml"), &variant).expect("valid");
        let report = run::run(&sc, &RunOptions::default());
        assert!(report.passed, "j = {j}: {}", report.verdict_line());
        let f = &report.motion.as_ref().expect("motion").frequencies[0];
        assert!(f.error <= 1e-9, "j = {j}: {}", f.error);
        assert!(f.simulation_error.is_some_and(|e| e <= 1e-9), "j = {j}: {:?}", f.simulation_error);
    }
}

const CATENARY: &str = "scenarios/custom/catenary.toml";

/// The catenary's numbers (the shipped file's parameters).
const CAT_L0_M: f64 = 10.0;
const CAT_EA_N: f64 = 1e4;
const CAT_RHO_KG_PER_M: f64 = 0.5;
const CAT_G: f64 = 9.81;
const CAT_H_N: f64 = 30.0;
const CAT_VA_N: f64 = 30.0;

/// Irvine's elastic catenary at unstretched arc length `s` from A: (x, z) [m].
fn irvine(s: f64) -> [f64; 2] {
    let (h, va, w, ea) = (CAT_H_N, CAT_VA_N, CAT_RHO_KG_PER_M * CAT_G, CAT_EA_N);
    let v = va - w * s;
    let x = h * s / ea + (h / w) * ((va / h).asinh() - (v / h).asinh());
    let z = -(w * s / ea) * (va / w - s / 2.0)
        - (h / w) * ((1.0 + (va / h).powi(2)).sqrt() - (1.0 + (v / h).powi(2)).sqrt());
    [x, z]
}

/// The catenary file with `segments` segments, its predictions left out (they name beads of
/// N = 20), so that any N runs.
fn catenary_with(segments: usize) -> tensegrity_testbed::report::ScenarioReport {
    let text = std::fs::read_to_string(CATENARY).unwrap();
    let head = &text[..text.find("# Each bead against").expect("the predictions")];
    let text = format!("{head}\n[expect]\nverdict = \"pass\"\n").replacen(
        "N = { value = 20,",
        &format!("N = {{ value = {segments},"),
        1,
    );
    let sc = scenario::parse(Path::new("catenary.toml"), &text).expect("valid");
    let report = run::run(&sc, &RunOptions::default());
    assert!(report.passed && report.points[0].settled, "N = {segments}: {}", report.verdict_line());
    report
}

/// The beads of the lumped chain of `segments` segments between A = 0 and B, solved exactly:
/// every segment carries (H, Z_1 + (j - 1) m g) (each bead's weight m g added, the anchors
/// taking the end halves), is straight and stretched to l0 / N (1 + T / EA); Newton on
/// (H, Z_1) puts its end at B. Returns the bead positions (x, z) [m].
fn discrete_chain(segments: usize, b: [f64; 2]) -> Vec<[f64; 2]> {
    let n = segments as f64;
    let weight = CAT_RHO_KG_PER_M * CAT_L0_M / n * CAT_G;
    let walk = |h: f64, z1: f64| -> Vec<[f64; 2]> {
        let mut p = [0.0, 0.0];
        let mut out = Vec::new();
        for j in 0..segments {
            let (fx, fz) = (h, z1 + j as f64 * weight);
            let t = fx.hypot(fz);
            let l = CAT_L0_M / n * (1.0 + t / CAT_EA_N);
            p = [p[0] + l * fx / t, p[1] + l * fz / t];
            out.push(p);
        }
        out
    };
    let (mut h, mut z1) = (CAT_H_N, -CAT_VA_N);
    for _ in 0..50 {
        let end = |h: f64, z1: f64| *walk(h, z1).last().unwrap();
        let r = end(h, z1);
        let (f0, f1) = (r[0] - b[0], r[1] - b[1]);
        let d = 1e-6;
        let (eh, ez) = (end(h + d, z1), end(h, z1 + d));
        let j = [[(eh[0] - r[0]) / d, (ez[0] - r[0]) / d], [(eh[1] - r[1]) / d, (ez[1] - r[1]) / d]];
        let det = j[0][0] * j[1][1] - j[0][1] * j[1][0];
        h -= (j[1][1] * f0 - j[0][1] * f1) / det;
        z1 -= (-j[1][0] * f0 + j[0][0] * f1) / det;
    }
    let mut beads = walk(h, z1);
    beads.pop();
    beads
}

/// The settled beads are the lumped chain's own equilibrium, solved apart (Newton on its two
/// end forces), within 1e-9 m: the simulation adds nothing to the discretisation's error.
#[test]
fn the_catenarys_beads_are_the_discrete_chains_equilibrium_within_1e_9_m() {
    let report = common::run_file(CATENARY);
    assert!(report.points[0].settled);
    let b = irvine(CAT_L0_M);
    for (i, want) in discrete_chain(20, b).iter().enumerate() {
        let got = common::node(&report, &format!("cable_b{}", i + 1));
        let err = (got[0] - want[0]).hypot(got[2] - want[1]);
        assert!(err <= 1e-9 && got[1].abs() <= 1e-12, "bead {}: {got:?} vs {want:?} ({err:e} m)", i + 1);
    }
}

/// Against Irvine's continuous catenary the lumped chain's error falls as 1/N^2: the largest
/// bead error over N = 10, 20, 40 has a fitted order within 0.1 of 2 (measured: 2.00), and is
/// 2.2e-3 m at the shipped N = 20.
#[test]
fn the_catenarys_error_against_irvine_falls_as_the_square_of_the_segment_length() {
    let counts = [10usize, 20, 40];
    let errors: Vec<f64> = counts
        .iter()
        .map(|&n| {
            let report = catenary_with(n);
            (1..n)
                .map(|i| {
                    let got = common::node(&report, &format!("cable_b{i}"));
                    let want = irvine(i as f64 * CAT_L0_M / n as f64);
                    (got[0] - want[0]).hypot(got[2] - want[1])
                })
                .fold(0.0, f64::max)
        })
        .collect();
    let lengths: Vec<f64> = counts.iter().map(|&n| CAT_L0_M / n as f64).collect();
    let order = common::fitted_order(&lengths, &errors);
    assert!((order - 2.0).abs() <= 0.1, "order {order}, errors {errors:?}");
    assert!(errors[1] <= 2.5e-3, "{errors:?}");
}

const PRISM_ELASTIC: &str = "scenarios/custom/prism3_elastic.toml";

/// A pin-jointed structure's equilibrium solved apart from the simulator: the positions of the
/// nodes on free bodies (every one a point mass here) that zero the net force of the members'
/// laws on each, by Levenberg-Marquardt from the drawing (the Jacobian by central differences;
/// the damping keeps the step finite along a free turn). Returns every node's position [m].
fn pin_jointed_equilibrium(s: &tensegrity_testbed::structure::Structure) -> Vec<[f64; 3]> {
    use nalgebra::{DMatrix, DVector};
    use tensegrity_testbed::structure::BodyKind;
    let free: Vec<usize> = (0..s.nodes.len()).filter(|&n| s.bodies[s.nodes[n].body].kind == BodyKind::Free).collect();
    let place = |x: &DVector<f64>| {
        let mut p: Vec<[f64; 3]> = s.nodes.iter().map(|n| n.position).collect();
        for (k, &n) in free.iter().enumerate() {
            p[n] = [x[3 * k], x[3 * k + 1], x[3 * k + 2]];
        }
        p
    };
    let residual = |x: &DVector<f64>| {
        let p = place(x);
        let mut f = vec![[0.0; 3]; s.nodes.len()];
        for m in &s.members {
            let law = m.elastic_law(m.rest_length_m().unwrap()).expect("every member has a law");
            let (a, b) = m.ends();
            let d = [0, 1, 2].map(|c| p[b][c] - p[a][c]);
            let l = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
            let t = law.tension_n(l);
            for c in 0..3 {
                f[a][c] += t * d[c] / l;
                f[b][c] -= t * d[c] / l;
            }
        }
        DVector::from_iterator(3 * free.len(), free.iter().flat_map(|&n| f[n]))
    };
    let mut x = DVector::from_iterator(3 * free.len(), free.iter().flat_map(|&n| s.nodes[n].position));
    let mut lambda = 1e-3;
    for _ in 0..500 {
        let r = residual(&x);
        if r.norm() < 1e-13 {
            break;
        }
        let h = 1e-7;
        let jac = DMatrix::from_fn(r.len(), x.len(), |i, j| {
            let (mut xp, mut xm) = (x.clone(), x.clone());
            xp[j] += h;
            xm[j] -= h;
            (residual(&xp)[i] - residual(&xm)[i]) / (2.0 * h)
        });
        let jtj = jac.transpose() * &jac;
        let step = (&jtj + DMatrix::identity(x.len(), x.len()) * lambda).lu().solve(&(-jac.transpose() * &r)).unwrap();
        let next = &x + step;
        if residual(&next).norm() < r.norm() {
            x = next;
            lambda = (lambda * 0.3).max(1e-15);
        } else {
            lambda *= 10.0;
        }
    }
    place(&x)
}

/// Every member's length [m], its nodes at `p`.
fn member_lengths(s: &tensegrity_testbed::structure::Structure, p: &[[f64; 3]]) -> Vec<f64> {
    s.members.iter().map(|m| m.length_at(|n| p[n])).collect()
}

/// The settled structure of a prism file: its (lowered) structure and every node's position.
fn settled_prism(text: &str) -> (tensegrity_testbed::structure::Structure, Vec<[f64; 3]>) {
    let sc = scenario::parse(Path::new("prism.toml"), text).expect("valid");
    let (s, _) = tensegrity_testbed::export::first_structure(&sc).expect("a structure");
    let report = run::run(&sc, &RunOptions::default());
    assert!(report.passed && report.points[0].settled, "{}", report.verdict_line());
    let p = s.nodes.iter().map(|n| common::node(&report, &n.name)).collect();
    (s, p)
}

/// The elastic-strut prism's settled member lengths are those of its pin-jointed equilibrium
/// solved apart, within 1e-10 m (the struts 4 % shorter than drawn under the cables' pull).
#[test]
fn the_elastic_prism_settles_where_the_pin_jointed_equilibrium_is_within_1e_10_m() {
    let (mut s, settled) = settled_prism(&std::fs::read_to_string(PRISM_ELASTIC).unwrap());
    // strut1 lies on the fixed body: its ends do not move, so it has no law to solve with.
    s.members.retain(|m| !m.is_rigid_strut());
    let solved = pin_jointed_equilibrium(&s);
    for ((got, want), m) in member_lengths(&s, &settled).iter().zip(member_lengths(&s, &solved)).zip(&s.members) {
        assert!((got - want).abs() <= 1e-10, "{}: {got} vs {want}", m.name);
    }
    let strut = s.member("strut2").unwrap();
    let shortening = 1.0 - member_lengths(&s, &solved)[s.member_id("strut2").unwrap()] / strut.rest_length_m().unwrap();
    assert!(shortening > 0.01, "the strut shortens: {shortening}");
}

/// As EA grows the elastic prism's cables take the rigid prism's lengths, with an error that
/// falls as 1/EA: fitted order within 0.05 of -1 over EA = 1e4, 1e5, 1e6 N (measured -1.00).
/// The step shrinks as 1 / sqrt(EA), as the struts' axial frequency grows (`physical.rs`
/// refuses a step that cannot follow it).
#[test]
fn the_elastic_prism_becomes_the_rigid_one_as_ea_grows_with_an_error_in_1_over_ea() {
    let rigid = std::fs::read_to_string("scenarios/custom/prism3.toml").unwrap();
    let (s_rigid, p_rigid) = settled_prism(&rigid);
    let cables = |s: &tensegrity_testbed::structure::Structure, p: &[[f64; 3]]| -> Vec<f64> {
        s.members
            .iter()
            .filter(|m| !matches!(m.kind(), tensegrity_testbed::structure::MemberKind::Strut))
            .map(|m| m.length_at(|n| p[n]))
            .collect()
    };
    let want = cables(&s_rigid, &p_rigid);
    let stiffness: [f64; 3] = [1e4, 1e5, 1e6];
    let errors: Vec<f64> = stiffness
        .iter()
        .map(|ea| {
            let dt = 0.005 * (1e4 / ea).sqrt();
            let (ea_line, dt_line) = (format!("EA = {{ value = {ea:?},"), format!("dt = {dt:?}"));
            let text = common::edited(PRISM_ELASTIC, &[("EA = { value = 2000.0,", &ea_line), ("dt = 0.005", &dt_line)]);
            let (s, p) = settled_prism(&text);
            cables(&s, &p).iter().zip(&want).map(|(g, w)| (g - w).abs()).fold(0.0, f64::max)
        })
        .collect();
    let order = common::fitted_order(&stiffness, &errors);
    assert!((order + 1.0).abs() <= 0.05, "order {order}, errors {errors:?}");
}

/// As the density goes to zero the heavy string under gravity becomes the massless one,
/// straight between its anchors: its largest sag falls as rho (fitted order within 0.05 of 1
/// over rho = 1e-2, 1e-3, 1e-4 kg/m; measured 1.00), and the first segment's tension's
/// distance from k (span - L0) as rho^2 (the sag stretches the string at second order;
/// measured 2.00). The step shrinks as sqrt(rho), as the beads' frequencies grow.
#[test]
fn a_heavy_string_becomes_the_massless_one_as_its_density_goes_to_zero_with_an_error_in_rho() {
    let densities: [f64; 3] = [1e-2, 1e-3, 1e-4];
    let massless_tension = K_N_PER_M * (SPAN_M - L0_M);
    let (mut sags, mut tension_errors) = (Vec::new(), Vec::new());
    for rho in densities {
        let dt = 0.0005 * (rho / RHO_KG_PER_M).sqrt();
        let (rho_line, dt_line) = (format!("rho = {{ value = {rho:?},"), format!("dt = {dt:?}"));
        let edits = [
            ("rho = { value = 0.3,", rho_line.as_str()),
            ("dt = 0.0005", dt_line.as_str()),
            ("gravity = [0, 0, 0]", "gravity = [0, 0, -9.81]"),
        ];
        let text = common::edited(BEADED, &edits);
        let head = &text[..text.find("[motion]").expect("the motion")];
        let sc =
            scenario::parse(Path::new("heavy.toml"), &format!("{head}[expect]\nverdict = \"pass\"\n")).expect("valid");
        let report = run::run(&sc, &RunOptions::default());
        assert!(report.passed && report.points[0].settled, "rho = {rho}: {}", report.verdict_line());
        let sag = (1..SEGMENTS).map(|i| common::node(&report, &format!("string_b{i}"))[2].abs()).fold(0.0, f64::max);
        sags.push(sag);
        tension_errors.push((report.points[0].simulated["string_s1.force"] - massless_tension).abs());
    }
    let order = common::fitted_order(&densities, &sags);
    assert!((order - 1.0).abs() <= 0.05, "order {order}, sags {sags:?}");
    let order = common::fitted_order(&densities, &tension_errors);
    assert!((order - 2.0).abs() <= 0.05, "order {order}, tension errors {tension_errors:?}");
}

/// d/dEA of the elastic strut's settled force and of its axial frequency meet their closed
/// forms (F = 2 k a EA / (EA + k L): dF/dEA = 2 k^2 a L / (EA + k L)^2; omega^2 = 4 (k + EA / L) / m:
/// d omega / dEA = 2 / (m L omega)) within 1e-8 relative, and the differences of settles within
/// 1e-7 (measured 1.6e-11 and 1.3e-11; the settles' own error 5e-9).
#[test]
fn the_elastic_struts_sensitivities_to_ea_meet_the_closed_form() {
    let file = "scenarios/custom/elastic_strut.toml";
    let sc = scenario::load(Path::new(file)).expect("shipped");
    let r = tensegrity_testbed::study::sensitivity(&sc, file, 0, true, None).expect("sensitivities");
    let (k, a, l, m, ea): (f64, f64, f64, f64, f64) = (100.0, 0.2, 1.0, 1.0, 1000.0);
    let ea_row = r.parameters.iter().find(|p| p.name == "EA").expect("EA");
    let at = |name: &str| r.outputs.iter().position(|o| o.name == name).expect(name);
    let rel = |a: f64, b: f64| (a - b).abs() / b.abs();
    let force = ea_row.derivatives[at("strut.force")];
    let want_force = -2.0 * k * k * a * l / (ea + k * l).powi(2);
    assert!(rel(force, want_force) <= 1e-8, "{force} vs {want_force}");
    let omega = (4.0 * (k + ea / l) / m).sqrt();
    let frequency = ea_row.derivatives[at("mode6.omega")];
    assert!(rel(frequency, 2.0 / (m * l * omega)) <= 1e-8, "{frequency} vs {}", 2.0 / (m * l * omega));
    let check = ea_row.check.as_ref().expect("checked");
    for name in ["strut.force", "mode6.omega"] {
        assert!(rel(ea_row.derivatives[at(name)], check[at(name)]) <= 1e-7, "{name}");
    }
}

/// EA fitted from a measured strut force and axial frequency (the truth EA = 900 N; the file's
/// 1000 N the start): the truth within the 95 % interval and within 1e-6 relative, the
/// interval's half-width 1.96 sigma with sigma the linearised model's for the force's
/// 1e-3 N: 1e-3 / (dF/dEA) over the frequency's share.
#[test]
fn ea_fitted_from_a_strut_force_and_an_axial_frequency_holds_the_truth() {
    use tensegrity_testbed::study::{fit, FitParameter, FitProblem, Measurement};
    let file = "scenarios/custom/elastic_strut.toml";
    let (k, a, l, m, truth): (f64, f64, f64, f64, f64) = (100.0, 0.2, 1.0, 1.0, 900.0);
    let force = -2.0 * k * a * truth / (truth + k * l);
    let omega = (4.0 * (k + truth / l) / m).sqrt();
    let row = |output: &str, value: f64| Measurement {
        at: output.to_string(),
        point: 0,
        output: output.to_string(),
        value,
        sigma: Some(1e-3),
        time_s: None,
    };
    let problem = FitProblem {
        file: file.into(),
        source: std::fs::read_to_string(file).unwrap(),
        overrides: Vec::new(),
        parameters: vec![FitParameter { name: "EA".into(), low: None, high: None }],
        measurements: vec![row("strut.force", force), row("mode6.omega", omega)],
    };
    let r = fit(&problem, None).expect("a fit");
    let ea = &r.parameters[0];
    assert!(ea.low <= truth && truth <= ea.high, "EA = {} in [{}, {}]", ea.value, ea.low, ea.high);
    assert!((ea.value / truth - 1.0).abs() <= 1e-6, "EA = {}", ea.value);
    let (df, dw) = (2.0 * k * k * a * l / (truth + k * l).powi(2), 2.0 / (m * l * omega));
    let sigma = 1e-3 / (df * df + dw * dw).sqrt();
    assert!((ea.sigma / sigma - 1.0).abs() <= 1e-3, "sigma {} vs {sigma}", ea.sigma);
}

/// Bad input on the new keys: exit 2 at the key, with what would do. (`tensegrity check`
/// exits 2 on each, as on any scenario error: `bad_input.rs`.)
#[test]
fn bad_elastic_strut_and_heavy_cable_keys_are_errors_at_their_key() {
    let strut = std::fs::read_to_string("scenarios/custom/elastic_strut.toml").unwrap();
    let with = |from: &str, to: &str| strut.replacen(from, to, 1);
    for (value, msg) in
        [("0.0", "EA (N) must be > 0"), ("-5.0", "EA (N) must be > 0"), ("nan", "must be a finite number")]
    {
        let text = with("EA = \"EA\"", &format!("EA = {value}"));
        common::error_at(&text, &format!("EA = {value}"), 5, msg);
    }
    let text = with("EA = \"EA\"", "E = 2e11");
    common::error_at(&text, "E = 2e11", 4, "E needs area");
    let text = with("EA = \"EA\"", "EA = \"EA\"\nE = 2e11\narea = 1e-4");
    common::error_at(&text, "E = 2e11", 4, "states EA already");
    let text = with("EA = \"EA\"", "E = 2e11\narea = 1e300");
    common::error_at(&text, "E = 2e11", 4, "not finite");
    let text = with("EA = \"EA\"", "EA = \"EA\"\nsegments = 3");
    common::error_at(&text, "segments = 3", 11, "'strut' is a strut; segments states a heavy cable's count");
    let text = with("stiffness = \"k\"\nlength = 0.0", "stiffness = \"k\"\nlength = 0.0\nEA = 5.0");
    common::error_at(&text, "EA = 5.0", 5, "the spring states its stiffness already");
    let text = with(
        "[[structure.bodies]]\nname = \"bar\"\nmass = \"m\"",
        "[[structure.bodies]]\nname = \"bar\"\nfixed = true",
    );
    common::error_at(&text, "EA = \"EA\"", 5, "its body 'bar' is fixed");
    let text = with("Q = [\"L\", 0, 0] }", "Q = [\"L\", 0, 0], R = [0.5, 0.1, 0] }");
    common::error_at(&text, "EA = \"EA\"", 5, "carries other nodes");
    let text = with("dt = 0.001", "dt = 0.05");
    common::error_at(&text, "dt = 0.05", 5, "the step is unstable from 2");

    let cable = std::fs::read_to_string(BEADED).unwrap();
    let with = |from: &str, to: &str| cable.replacen(from, to, 1);
    for (value, msg) in
        [("0", "from 1 to 1000"), ("1001", "from 1 to 1000"), ("2.5", "whole number"), ("-3", "from 1 to 1000")]
    {
        let text = with("segments = \"N\"", &format!("segments = {value}"));
        common::error_at(&text, &format!("segments = {value}"), 11, msg);
    }
    for (value, msg) in [("0.0", "density (kg/m) must be > 0"), ("-1.0", "must be > 0"), ("inf", "finite")] {
        let text = with("density = \"rho\"", &format!("density = {value}"));
        common::error_at(&text, &format!("density = {value}"), 10, msg);
    }
    let text = with("density = \"rho\"\n", "");
    common::error_at(&text, "segments = \"N\"", 11, "segments means nothing without density");
    // Five beads have 15 modes: their turns are none (`structure::modal_bodies`).
    let text = with("mode = 1              #", "mode = 16             #");
    common::error_at(&text, "mode = 16", 7, "mode 16 does not exist: the structure has 15");
    let text = with("segments = \"N\"\n", "");
    common::error_at(&text, "density = \"rho\"", 10, "a heavy cable needs segments");
    let text = with("stiffness = \"k\"\n", "");
    common::error_at(&text, "density = \"rho\"", 10, "an inextensible heavy cable is not modelled");
    let text = with("density = \"rho\"", "density = \"rho\"\nEA = 1.0");
    common::error_at(&text, "EA = 1.0", 5, "'string' is a cable; EA states a strut's axial stiffness");
    let text = with("[[structure.cables]]\nname = \"string\"", "[[structure.bodies]]\nname = \"string_b1\"\nfixed = true\nnodes = { X = [0, 1, 0] }\n\n[[structure.cables]]\nname = \"string\"");
    common::error_at(&text, "density = \"rho\"", 10, "it would name a part 'string_b1'");
}

/// A heavy cable that cannot be built is refused by name: through an inner node where a bead
/// would sit (the string through M at its middle, 6 segments: bead 3 on M; 5 segments build),
/// from a rigid free body (its end's mass would have no place), driven by a winch.
#[test]
fn a_heavy_cable_that_cannot_be_built_is_refused_by_name() {
    let cable = std::fs::read_to_string(BEADED).unwrap();
    let mid = cable.replacen("B = [\"span\", 0, 0] }", "B = [\"span\", 0, 0], M = [0.6, 0.3, 0] }", 1);
    let text = mid.replacen("b = \"B\"\n", "b = \"B\"\nthrough = [\"M\"]\n", 1);
    common::error_at(&text, "density = \"rho\"", 10, "a bead would sit on its inner node 'M'");
    let odd = text.replacen("N = { value = 6,", "N = { value = 5,", 1);
    assert!(scenario::parse(Path::new("odd.toml"), &odd).is_ok(), "5 segments put no bead on M");
    let rigid = "[[structure.bodies]]\nname = \"plate\"\nmass = 1.0\nnodes = { C = [1.2, 0, 0], D = [1.2, 0.2, 0] }\n\n[[structure.cables]]";
    let text = cable
        .replacen("B = [\"span\", 0, 0] }", "B0 = [\"span\", 0, 0] }", 1)
        .replacen("[[structure.cables]]", rigid, 1)
        .replacen("b = \"B\"", "b = \"C\"", 1);
    common::error_at(&text, "density = \"rho\"", 10, "free body 'plate', which is not a point mass");
    let winch = "[[structure.actuators]]\nsymbol = \"w\"\ncable = \"string\"\n\n[motion]";
    let text = cable.replacen("[motion]", winch, 1);
    common::error_at(&text, "density = \"rho\"", 10, "a winch drives it");
}

/// `modes --json` gives each non-rigid mode's shape: the beaded string's lowest mode moves bead
/// i by a sin(pi i / (n + 1)) in one direction across the string (within 1e-9 of the largest),
/// the anchors not at all, mass-normalised: sum m |d_i|^2 = 1 within 1e-12.
#[test]
fn the_beaded_strings_mode_shape_is_the_sine_of_the_closed_form() {
    let (code, out, err) = common::tensegrity(&["modes", BEADED, "--json", "-"]);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    let shape = v["modes"][0]["node_displacements_m"].as_array().expect("the shape");
    let at = |name: &str| -> [f64; 3] {
        let row = shape.iter().find(|r| r[0] == name).unwrap_or_else(|| panic!("{name}"));
        [0, 1, 2].map(|k| row[1][k].as_f64().unwrap())
    };
    assert_eq!(at("A"), [0.0; 3]);
    let n = SEGMENTS - 1;
    let d: Vec<[f64; 3]> = (1..=n).map(|i| at(&format!("string_b{i}"))).collect();
    let (u, top) = (d[2], (d[2][1].hypot(d[2][2])));
    assert!(u[0].abs() <= 1e-12 * top, "across the string: {u:?}");
    let m = RHO_KG_PER_M * L0_M / SEGMENTS as f64;
    let mut norm = 0.0;
    for (i, di) in d.iter().enumerate() {
        let sine = ((i + 1) as f64 * std::f64::consts::PI / (n + 1) as f64).sin();
        for k in 0..3 {
            assert!((di[k] - sine * u[k]).abs() <= 1e-9 * top, "bead {}: {di:?} vs {sine} x {u:?}", i + 1);
        }
        norm += m * (di[0] * di[0] + di[1] * di[1] + di[2] * di[2]);
    }
    assert!((norm - 1.0).abs() <= 1e-12, "v^T M v = {norm}");
}

/// The static relaxation keeps Newton's pace on a structure whose light beads are 1e10 times
/// stiffer (mass-weighted) than its soft modes: the 150-strut prism of
/// `benches/prism_elastic_heavy.toml` (elastic struts, 10-segment heavy cables of 0.05 kg/m:
/// 3 beads of 0.2 g per mm) settles to the rigid prism's residual of 1e-10 N in at most 25
/// steps (measured 17). Its shift's metric weighs the point masses at the heaviest body's
/// mass, and a step below the energy's round-off is still taken where it halves a force above
/// the force's own. Before, the shift's floor (1e-9 of the beads' stiffest mode) left the soft
/// modes to close 13 % of their gap a step (300 struts: 101 steps), and from 150 struts on
/// the relaxation stalled at about 8e-9 N, short of 1e-10 N.
#[test]
fn a_prism_with_light_beads_settles_in_newtons_steps() {
    let text = std::fs::read_to_string("benches/prism_elastic_heavy.toml")
        .unwrap()
        .replace("n = { value = 300,", "n = { value = 150,");
    let sc = scenario::parse(Path::new("prism150_heavy.toml"), &text).unwrap();
    assert_eq!(sc.settle.residual_force_tol_n, 1e-10);
    let report = run::run(&sc, &RunOptions::default());
    let point = &report.points[0];
    assert!(report.passed && point.settled, "{}", report.verdict_line());
    assert!(point.steps <= 25, "{} steps", point.steps);
    assert!(point.residual_force_n <= 1e-10, "residual {} N", point.residual_force_n);
}

/// Irvine's elastic catenary of the catenary file's cable, started with horizontal tension `h`
/// and vertical reaction `va` [N]: the point at unstretched arc length `s` from its start
/// (x, z) [m].
fn irvine_from(h: f64, va: f64, s: f64) -> [f64; 2] {
    let (w, ea) = (CAT_RHO_KG_PER_M * CAT_G, CAT_EA_N);
    let v = va - w * s;
    let x = h * s / ea + (h / w) * ((va / h).asinh() - (v / h).asinh());
    let z = -(w * s / ea) * (va / w - s / 2.0)
        - (h / w) * ((1.0 + (va / h).powi(2)).sqrt() - (1.0 + (v / h).powi(2)).sqrt());
    [x, z]
}

/// The catenary's cable run over a frictionless pulley P (a fixed inner node) at unstretched
/// arc length `PULLEY_ARC_M`, which turns it down by `PULLEY_TURN_RAD`: the tension is the
/// same on both sides of P (no friction), so the second leg is Irvine's catenary from P with
/// the first leg's end tension turned by the angle. The exact shape (x, z) at arc length s.
const PULLEY_ARC_M: f64 = 4.5;
const PULLEY_TURN_RAD: f64 = 0.25;

fn over_the_pulley(s: f64) -> [f64; 2] {
    if s <= PULLEY_ARC_M {
        return irvine(s);
    }
    let v = CAT_VA_N - CAT_RHO_KG_PER_M * CAT_G * PULLEY_ARC_M;
    let (t, angle) = (CAT_H_N.hypot(v), v.atan2(CAT_H_N) + PULLEY_TURN_RAD);
    let (p, rest) = (irvine(PULLEY_ARC_M), irvine_from(t * angle.cos(), t * angle.sin(), s - PULLEY_ARC_M));
    [p[0] + rest[0], p[1] + rest[1]]
}

/// The pulley's file with `segments` segments: the catenary's cable from A through P to B.
fn pulley_with(segments: usize) -> tensegrity_testbed::report::ScenarioReport {
    let (p, b) = (over_the_pulley(PULLEY_ARC_M), over_the_pulley(CAT_L0_M));
    let text = format!(
        r#"name = "a heavy cable over a frictionless pulley"
mechanism = "custom"

[sim]
dt = 0.0005
body_damping = 20.0

[settle]
speed_tol = 1e-10
residual_force_tol = 1e-9
residual_torque_tol = 1e-9
max_time = 60.0

[actuation]
points = [ {{}} ]

[structure]
gravity = [0, 0, -{CAT_G}]

[[structure.bodies]]
name = "ground"
fixed = true
nodes = {{ A = [0, 0, 0], P = [{}, 0, {}], B = [{}, 0, {}] }}

[[structure.cables]]
name = "cable"
a = "A"
through = ["P"]
b = "B"
stiffness = {}
length = {CAT_L0_M}
density = {CAT_RHO_KG_PER_M}
segments = {segments}

[expect]
verdict = "pass"
"#,
        p[0],
        p[1],
        b[0],
        b[1],
        CAT_EA_N / CAT_L0_M
    );
    let sc = scenario::parse(Path::new("pulley.toml"), &text).expect("valid");
    let report = run::run(&sc, &RunOptions::default());
    assert!(report.passed && report.points[0].settled, "N = {segments}: {}", report.verdict_line());
    report
}

/// A heavy clustered cable slides through its inner node: the catenary's cable over a
/// frictionless pulley that turns it by 0.25 rad settles on the exact two-leg catenary (equal
/// tensions on both sides of P), its largest bead error falling as 1/N^2 over N = 10, 30, 50
/// (fitted order within 0.15 of 2; P at 0.45 L0 lies mid-segment at each N, so that the
/// kink's place in its segment is the same at each).
#[test]
fn a_heavy_cable_over_a_frictionless_pulley_settles_on_the_two_leg_catenary() {
    let counts = [10usize, 30, 50];
    let errors: Vec<f64> = counts
        .iter()
        .map(|&n| {
            let report = pulley_with(n);
            (1..n)
                .map(|i| {
                    let got = common::node(&report, &format!("cable_b{i}"));
                    let want = over_the_pulley(i as f64 * CAT_L0_M / n as f64);
                    (got[0] - want[0]).hypot(got[2] - want[1])
                })
                .fold(0.0, f64::max)
        })
        .collect();
    let lengths: Vec<f64> = counts.iter().map(|&n| CAT_L0_M / n as f64).collect();
    let order = common::fitted_order(&lengths, &errors);
    assert!((order - 2.0).abs() <= 0.15, "order {order}, errors {errors:?}");
    eprintln!("pulley: errors {errors:?}, order {order}");
}

/// A strut may state its density (kg/m) in place of its body's mass: the body gets
/// m = rho L and a thin bar's moments m L^2 / 12 (to 1e-15 relative); an elastic strut's two
/// point masses then hold rho L / 2 each. Where the body also states its mass, carries other
/// nodes, or is fixed, the density is an error at its key.
#[test]
fn a_struts_density_gives_its_body_its_mass() {
    let file = std::fs::read_to_string("scenarios/custom/elastic_strut.toml").unwrap();
    let dense = file.replacen("mass = \"m\"\n", "", 1).replacen("EA = \"EA\"", "density = 2.5", 1);
    let sc = scenario::parse(Path::new("dense.toml"), &dense).expect("valid");
    let (s, _) = tensegrity_testbed::export::first_structure(&sc).expect("a structure");
    let length = 1.0; // the file's L
    let bar = s.bodies.iter().find(|b| b.name == "bar").unwrap().inertia.unwrap();
    let mass = 2.5 * length;
    assert!((bar.mass_kg - mass).abs() <= 1e-15 * mass, "{} kg", bar.mass_kg);
    for moment in bar.principal_kg_m2 {
        assert!((moment - mass * length * length / 12.0).abs() <= 1e-15 * moment, "{moment} kg m^2");
    }
    let elastic = file.replacen("mass = \"m\"\n", "", 1).replacen("EA = \"EA\"", "EA = \"EA\"\ndensity = 2.5", 1);
    let sc = scenario::parse(Path::new("elastic.toml"), &elastic).expect("valid");
    let (s, _) = tensegrity_testbed::export::first_structure(&sc).expect("a structure");
    let halves: Vec<f64> = s.bodies.iter().filter_map(|b| b.inertia).map(|i| i.mass_kg).collect();
    assert_eq!(halves.len(), 2);
    assert!(halves.iter().all(|m| (m - mass / 2.0).abs() <= 1e-15 * mass), "{halves:?}");
    let both = file.replacen("EA = \"EA\"", "density = 2.5", 1);
    common::error_at(&both, "density = 2.5", 10, "and the body states its mass: state one");
    let other = dense.replacen("Q = [\"L\", 0, 0] }", "Q = [\"L\", 0, 0], R = [0, 1, 0] }", 1);
    common::error_at(&other, "density = 2.5", 10, "its body carries other nodes");
    let fixed = dense.replacen("name = \"bar\"\n", "name = \"bar\"\nfixed = true\n", 1);
    common::error_at(&fixed, "density = 2.5", 10, "its body is fixed");
}

/// A bar of EA = 25e6 N drawn 1 m long with `length = 1.001` m, both ends held by supports:
/// a prestressed bar pushing with EA (L - L0) / L0 = -24975.02 N (relative 1e-12), where
/// `length` had been ignored and the bar settled at 0 N. On a rigid strut `length`, and on any
/// strut `stiffness`, is an error at the key.
#[test]
fn an_elastic_struts_length_is_its_rest_length() {
    let text = common::one_point_head("a prestressed bar")
        + r#"[[structure.bodies]]
name = "bar"
mass = 2.0
nodes = { A = [0, 0, 0], B = [1, 0, 0] }

[[structure.struts]]
name = "bar"
a = "A"
b = "B"
EA = 25e6
length = 1.001

[[structure.supports]]
node = "A"
fixed = ["x", "y", "z"]

[[structure.supports]]
node = "B"
fixed = ["x", "y", "z"]
"#;
    let sc = scenario::parse(Path::new("bar.toml"), &text).expect("valid");
    let report = run::run(&sc, &RunOptions::default());
    let force = report.points[0].simulated["bar.force"];
    let want = 25e6 * (1.0 - 1.001) / 1.001;
    assert!((force - want).abs() <= 1e-12 * want.abs(), "{force} against {want}");
    let rigid = text.replacen("EA = 25e6\n", "", 1);
    common::error_at(&rigid, "1.001", 0, "a rigid strut keeps its drawn length");
    let stiff = text.replacen("EA = 25e6\n", "stiffness = 3.0\n", 1);
    common::error_at(&stiff, "3.0", 0, "a strut's stiffness is EA / L");
}
