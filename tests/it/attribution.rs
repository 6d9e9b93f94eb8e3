//! What each idealization costs a model (`[[fidelity]]`, `tensegrity attribute`): every share
//! against a closed form, the shares adding up, and bad relaxations refused at their table.

use super::common;

const HANGING: &str = "tests/fixtures/attribution/hanging_bar.toml";
const G: f64 = 9.81;

/// The single compared value's (shares, interaction, deviation at every level) of `report`.
fn only_item(v: &serde_json::Value) -> (Vec<f64>, f64, Vec<f64>) {
    let items = v["items"].as_array().unwrap();
    assert_eq!(items.len(), 1, "{items:?}");
    let f = |x: &serde_json::Value| x.as_array().unwrap().iter().map(|s| s.as_f64().unwrap()).collect::<Vec<f64>>();
    (f(&items[0]["shares"]), items[0]["interaction"].as_f64().unwrap(), f(&items[0]["deviation"]))
}

/// A bar (M = 2 kg, L = 0.5 m) on a cable (l = 1 m) under gravity: the elastic bar (EA_s = 1e4 N)
/// lowers its end by M g L / (2 EA_s), the elastic cable (EA_c = 1e3 N) by M g l / EA_c, the
/// heavy cable (rho = 0.1 kg/m, n = 4, measured on the elastic cable) by rho g l^2 / (2 EA_c),
/// each within 1e-9 m. They add: the interaction is below 1e-12 m, and the shares and the
/// interaction add up to the whole change within 1e-15 m.
#[test]
fn each_relaxation_of_a_hanging_bar_costs_its_closed_form_and_the_shares_add_up() {
    let v = common::json_of("attribute", &std::fs::read_to_string(HANGING).unwrap(), "hanging");
    let (shares, interaction, deviation) = only_item(&v);
    assert_eq!(v["relaxations"][1]["assumption"], "inextensible cables");
    let (m, bar, l, ea_s, ea_c, rho) = (2.0, 0.5, 1.0, 1e4, 1e3, 0.1);
    let heavy_all = rho * G * l * l / (2.0 * ea_c);
    let want = [-m * G * bar / (2.0 * ea_s), -m * G * l / ea_c, -heavy_all];
    for (got, want) in shares.iter().zip(want) {
        assert!((got - want).abs() <= 1e-9, "share {got} against {want}");
    }
    assert!(interaction.abs() <= 1e-12, "interaction {interaction}");
    assert_eq!(deviation[0], 0.0, "the ideal run settles at the model's depth");
    let all = *deviation.last().unwrap();
    let added = deviation[0] + shares.iter().sum::<f64>() + interaction;
    assert!((all - added).abs() <= 1e-15, "{all} against {added}");
    let levels: Vec<&str> = v["levels"].as_array().unwrap().iter().map(|l| l["name"].as_str().unwrap()).collect();
    assert_eq!(levels, ["ideal", "elastic bar", "elastic cable", "heavy cable", "all"]);
    assert_eq!(v["relaxations"][2]["on_top_of"][0], "elastic cable");
}

/// A relaxation stated as parameter values (the bar 3 kg, not 2): alone, on the rigid bar and
/// the inextensible cable, it moves nothing (exactly 0); with the elastic members it adds
/// the extra kilogram's stretch, -g (l / EA_c + L / (2 EA_s)) = -1.005525e-2 m, all of it in
/// the interaction, within 1e-9 m.
#[test]
fn a_relaxation_by_parameter_values_shows_in_the_interaction() {
    let text = std::fs::read_to_string(HANGING).unwrap()
        + "\n[[fidelity]]\nname = \"heavier bar\"\nrelax = \"parameter values\"\nset = { M = 3.0 }\n";
    let v = common::json_of("attribute", &text, "heavier");
    let (shares, interaction, _) = only_item(&v);
    assert_eq!(shares[3], 0.0, "{shares:?}");
    let want = -G * (1.0 / 1e3 + 0.5 / (2.0 * 1e4));
    assert!((interaction - want).abs() <= 1e-9, "{interaction} against {want}");
    let bad = text.replace("set = { M = 3.0 }", "set = { mass = 3.0 }");
    let err = tensegrity_testbed::scenario::parse(std::path::Path::new("variant.toml"), &bad).expect_err("mass");
    assert!(err.message.contains("'mass' is not a parameter"), "{err}");
}

/// The CSV holds one row per compared value with every level's deviation, every share and the
/// interaction; the figure is an SVG with a bar per value.
#[test]
fn attribution_writes_its_csv_and_its_figure() {
    let dir = std::env::temp_dir().join(format!("tensegrity-attribution-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let (csv, svg) = (dir.join("a.csv"), dir.join("a.svg"));
    let (code, out, err) =
        common::tensegrity(&["attribute", HANGING, "--csv", csv.to_str().unwrap(), "--figure", svg.to_str().unwrap()]);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("interaction"), "{out}");
    let text = std::fs::read_to_string(&csv).unwrap();
    let header: Vec<&str> = text.lines().next().unwrap().split(',').collect();
    assert_eq!(header.len(), 4 + 5 + 3 + 1, "{header:?}");
    assert_eq!(header[12], "interaction");
    assert_eq!(text.lines().count(), 2);
    let figure = std::fs::read_to_string(&svg).unwrap();
    assert!(figure.starts_with("<svg") && figure.contains("heavy cable"), "{}", &figure[..200.min(figure.len())]);
    let _ = std::fs::remove_dir_all(&dir);
}

/// Bad relaxations are errors at their table: a member that does not exist, one the assumption
/// does not hold for, missing data, a structure that cannot take it (an elastic strut held by
/// a joint), an unknown assumption, and E without area. A file without relaxations is exit 2.
#[test]
fn bad_relaxations_are_refused_at_their_table() {
    let text = std::fs::read_to_string(HANGING).unwrap();
    let cases = [
        (
            "relax = \"rigid struts\"\nEA = 1e4",
            "relax = \"rigid struts\"\nEA = 1e4\nmembers = [\"rod\"]",
            "no member 'rod'",
        ),
        (
            "relax = \"rigid struts\"\nEA = 1e4",
            "relax = \"rigid struts\"\nEA = 1e4\nmembers = [\"cable\"]",
            "is a cable that is not one of the rigid struts",
        ),
        ("relax = \"inextensible cables\"\nEA = 1e3", "relax = \"inextensible cables\"", "needs EA"),
        (
            "relax = \"rigid struts\"\nEA = 1e4",
            "relax = \"rigid bodies\"\nEA = 1e4",
            "unknown assumption 'rigid bodies'",
        ),
        ("relax = \"rigid struts\"\nEA = 1e4", "relax = \"rigid struts\"\nE = 2e11", "E and area go together"),
        ("density = 0.1\nsegments = 4", "density = 0.1\nsegments = 0", "segments must be 1 to 1000"),
    ];
    for (from, to, msg) in cases {
        let variant = text.replacen(from, to, 1);
        let err = tensegrity_testbed::scenario::parse(std::path::Path::new("variant.toml"), &variant).expect_err(msg);
        assert!(err.message.contains(msg), "{msg}: {err}");
        let table = variant[..variant.find(to).unwrap()].rfind("[[fidelity]]").unwrap();
        let (line, _) = common::line_col(&variant, table);
        assert!(err.line >= line && err.line <= line + 8, "{msg}: at line {} for the table at {line}", err.line);
    }
    let path = std::env::temp_dir().join(format!("tensegrity-no-fidelity-{}.toml", std::process::id()));
    std::fs::write(&path, &text[..text.find("[[fidelity]]").unwrap()]).unwrap();
    let (code, _, err) = common::tensegrity(&["attribute", path.to_str().unwrap()]);
    let _ = std::fs::remove_file(&path);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("no [[fidelity]] relaxation"), "{err}");
}

/// An elastic strut needs a body of its own: a pinned bar's body is held by its joint, and the
/// relaxation says so at its table.
#[test]
fn a_relaxation_the_structure_cannot_take_is_refused_naming_why() {
    let text = std::fs::read_to_string("scenarios/custom/pinned_bar_modes.toml").unwrap()
        + "\n[[structure.struts]]\nname = \"rod\"\na = \"A\"\nb = \"P\"\n"
        + "\n[[fidelity]]\nrelax = \"rigid struts\"\nEA = 1e6\n";
    let err = tensegrity_testbed::scenario::parse(std::path::Path::new("variant.toml"), &text).expect_err("joint");
    assert!(err.message.contains("holds its body"), "{err}");
    let (line, _) = common::line_col(&text, text.rfind("[[fidelity]]").unwrap());
    assert_eq!(err.line, line, "{err}");
}

/// Every seed's attribution file runs: its ideal level gives the file's verdict, and at every
/// compared value the shares and the interaction add up to the whole change within 1e-12 of
/// the model's value (where the levels settled).
#[test]
fn every_seed_attributes_and_its_shares_add_up() {
    for file in [
        "scenarios/ji2014/gravity_attribution.toml",
        "scenarios/mohr2011/cable_attribution.toml",
        "scenarios/furet2018/gravity_attribution.toml",
        "scenarios/manriquez2019/table5_attribution.toml",
    ] {
        let (code, out, err) = common::tensegrity(&["attribute", file, "--json", "-"]);
        assert_eq!(code, 0, "{file}: {err}");
        let v: serde_json::Value = serde_json::from_str(&out).unwrap();
        assert_eq!(v["levels"][0]["as_expected"], true, "{file}: the ideal level's verdict");
        let levels = v["levels"].as_array().unwrap();
        let every = v["relaxations"].as_array().unwrap().len();
        let all_level = levels.iter().position(|l| l["relaxed"].as_array().unwrap().len() == every).unwrap();
        let mut added = 0;
        for it in v["items"].as_array().unwrap() {
            let d: Vec<f64> =
                it["deviation"].as_array().unwrap().iter().map(|x| x.as_f64().unwrap_or(f64::NAN)).collect();
            let shares: f64 = it["shares"].as_array().unwrap().iter().map(|x| x.as_f64().unwrap_or(f64::NAN)).sum();
            let all = d[all_level];
            let interaction = it["interaction"].as_f64().unwrap_or(f64::NAN);
            if all.is_nan() {
                continue;
            }
            let scale = it["model"].as_f64().unwrap().abs().max(1.0);
            assert!((d[0] + shares + interaction - all).abs() <= 1e-12 * scale, "{file}: {it}");
            added += 1;
        }
        // mohr2011's points 1 and 2 do not settle under gravity (FINDINGS.md): its first
        // point's seven values are compared; every other file compares 16 or more.
        assert!(added >= 7, "{file}: {added} values compared");
    }
}

/// manriquez2019's Table 5 against the relaxations (FINDINGS.md): the cables' weight raises the
/// joint force by 33.4 mN at every experiment (the ANSYS column lowers it), the elastic cables
/// change it by less than 0.2 mN, and both leave the cable forces' differences unexplained.
#[test]
fn manriquez2019_table5_the_relaxations_do_not_explain_the_joint_force() {
    let v = common::json_of(
        "attribute",
        &std::fs::read_to_string("scenarios/manriquez2019/table5_attribution.toml").unwrap(),
        "table5",
    );
    let joint: Vec<&serde_json::Value> =
        v["items"].as_array().unwrap().iter().filter(|it| it["name"] == "f_joint").collect();
    assert_eq!(joint.len(), 4);
    for it in joint {
        let (elastic, heavy) = (it["shares"][0].as_f64().unwrap(), it["shares"][1].as_f64().unwrap());
        assert!(elastic.abs() < 2e-4, "{it}");
        assert!((heavy - 0.0334).abs() < 2e-4, "{it}");
    }
}

/// The rest of the refusals at a relaxation's table: a step too long for the point masses a
/// relaxation makes, a heavy cable on a winch that the run moves after its build (continuation),
/// and "no gravity" without its gravity.
#[test]
fn a_relaxation_the_run_cannot_step_or_drive_is_refused_at_its_table() {
    let hanging = std::fs::read_to_string(HANGING).unwrap();
    let parse = |text: &str| tensegrity_testbed::scenario::parse(std::path::Path::new("variant.toml"), text);
    let err = parse(&hanging.replacen("dt = 0.001", "dt = 0.05", 1)).expect_err("step");
    assert!(err.message.contains("the step sim.dt = 0.05 s is unstable"), "{err}");
    let mohr = std::fs::read_to_string("scenarios/mohr2011/cable_attribution.toml").unwrap();
    let driven = mohr.replacen("[actuation]\ncontinuation = false", "[actuation]\ncontinuation = true", 1);
    assert_ne!(driven, mohr);
    let err = parse(&driven).expect_err("winch");
    assert!(err.message.contains("the winch no longer moves it"), "{err}");
    let gravity = hanging + "\n[[fidelity]]\nname = \"upright\"\nrelax = \"no gravity\"\n";
    let err = parse(&gravity).expect_err("gravity");
    assert!(err.message.contains("relaxing no gravity needs gravity"), "{err}");
}
