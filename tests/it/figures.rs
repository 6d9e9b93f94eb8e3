//! Figures are drawn as PNG and SVG, with their axes and the dynamics' overlay.

use std::process::Command;

#[test]
fn ji2014_fig4_is_drawn_as_png_and_svg() {
    let dir = std::env::temp_dir().join(format!("tensegrity-fig-{}", std::process::id()));
    let out = Command::new(env!("CARGO_BIN_EXE_tensegrity"))
        .args(["figure", "ji2014-fig4", "--out", dir.to_str().unwrap()])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0), "{}", String::from_utf8_lossy(&out.stderr));
    let png = std::fs::read(dir.join("ji2014-fig4.png")).unwrap();
    assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n", "a PNG file");
    assert!(png.len() > 10_000);
    let svg = std::fs::read_to_string(dir.join("ji2014-fig4.svg")).unwrap();
    for text in ["theta2 [rad]", "U [J] (Eq. 4)", "K [N m/rad] (Eq. 42)", "dynamics settled at theta2"] {
        assert!(svg.contains(text), "the SVG has '{text}'");
    }
    // The curves drawn are the data: U, tau and K each at the 721 samples of theta2 in
    // [-pi, pi] (FIG4_SAMPLES), left to right, and K = u0 - U (Eq. 42 and Eq. 4) drawn as U's
    // mirror image: their pixel heights correlate at -1 (to 1e-3, the pixels' rounding).
    let curves: Vec<Vec<(f64, f64)>> = polylines(&svg).into_iter().filter(|c| c.len() > 3).collect();
    assert_eq!(curves.iter().map(Vec::len).collect::<Vec<_>>(), vec![721; 3], "U, tau and K");
    assert!(curves.iter().all(|c| c.windows(2).all(|w| w[1].0 >= w[0].0)), "theta2 ascending");
    let heights = |c: &Vec<(f64, f64)>| c.iter().map(|p| p.1).collect::<Vec<f64>>();
    let r = correlation(&heights(&curves[0]), &heights(&curves[2]));
    assert!((r + 1.0).abs() < 1e-3, "corr(U, K) = {r}");
    let unknown = Command::new(env!("CARGO_BIN_EXE_tensegrity")).args(["figure", "no-such-figure"]).output().unwrap();
    assert_eq!(unknown.status.code(), Some(2));
}

#[test]
fn mohr2011_fig5_shows_the_slice_and_the_dynamics_verdict() {
    let dir = std::env::temp_dir().join(format!("tensegrity-fig5-{}", std::process::id()));
    let out = Command::new(env!("CARGO_BIN_EXE_tensegrity"))
        .args(["figure", "mohr2011-fig5", "--out", dir.to_str().unwrap()])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0), "{}", String::from_utf8_lossy(&out.stderr));
    let svg = std::fs::read_to_string(dir.join("mohr2011-fig5.svg")).unwrap();
    for text in ["x [m]", "y [m]", "static workspace (Eq. 29-31)", "agreement 100.0 %"] {
        assert!(svg.contains(text), "the SVG has '{text}'");
    }
}

/// Draws figure `name` into a fresh directory; returns the PNG bytes and the SVG text.
fn draw(name: &str) -> (Vec<u8>, String) {
    let dir = std::env::temp_dir().join(format!("tensegrity-{name}-{}", std::process::id()));
    let out = Command::new(env!("CARGO_BIN_EXE_tensegrity"))
        .args(["figure", name, "--out", dir.to_str().unwrap()])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0), "{}", String::from_utf8_lossy(&out.stderr));
    let png = std::fs::read(dir.join(format!("{name}.png"))).unwrap();
    assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n", "a PNG file");
    assert!(png.len() > 10_000);
    let svg = std::fs::read_to_string(dir.join(format!("{name}.svg"))).unwrap();
    assert!(svg.starts_with("<svg"), "an SVG file");
    (png, svg)
}

/// The number printed in `svg` right after `before` (digits, sign, point and exponent).
fn number_after(svg: &str, before: &str) -> f64 {
    let at = svg.find(before).unwrap_or_else(|| panic!("the SVG has '{before}'")) + before.len();
    let text: String = svg[at..].chars().take_while(|c| c.is_ascii_digit() || ".-+e".contains(*c)).collect();
    text.parse().unwrap_or_else(|_| panic!("a number after '{before}': '{text}'"))
}

#[test]
fn ji2014_fig2_shows_the_singular_curves_and_the_grid_verdict() {
    let (_, svg) = draw("ji2014-fig2");
    for text in ["theta1 [rad]", "L3 [m]", "det J [m/rad]", "110 of 110 points agree (100.0 %)", "(7 of 110 points)"] {
        assert!(svg.contains(text), "the SVG has '{text}'");
    }
    // Curve i is singular but stiff: K = (L/2)|eta| at L3 = 0 (FINDINGS.md: 346.41 N m/rad).
    assert!((number_after(&svg, "but not free: K = ") - 346.4).abs() < 0.05);
    // Curve ii is not singular: FINDINGS.md's smallest |det J| for L3 >= 0.3 m is 0.118 m/rad.
    assert!((number_after(&svg, "NOT singular, det J &gt;= ") - 0.118).abs() < 1e-3);
}

#[test]
fn ji2014_fig3_maps_the_workspace_and_the_settled_d3() {
    let (_, svg) = draw("ji2014-fig3");
    for text in ["x [m]", "y [m]", "110 of 110 settled D3 agree", "Eq. 37 as printed"] {
        assert!(svg.contains(text), "the SVG has '{text}'");
    }
    // Curve i (L3 = 0) maps to the single point D3 = (-sqrt3/2, -1/2) L (FINDINGS.md, Eq. 26).
    assert!((number_after(&svg, "maps to ONE point (") + 0.866).abs() < 1e-3);
    // The stable equilibria cover 4.17 m^2 of the plane (160 x 160 cells over 6.4 m x 4.8 m).
    assert!((number_after(&svg, "stable equilibrium of one input (L3, theta1): ") - 4.17).abs() < 0.02);
}

#[test]
fn ji2014_fig7_maps_the_stiffness_with_the_probe() {
    let (_, svg) = draw("ji2014-fig7");
    for text in ["theta1 [rad]", "L3 [m]", "K [N m/rad]", "(0 points; tolerance 1e-4)"] {
        assert!(svg.contains(text), "the SVG has '{text}'");
    }
    // The probe measures K of Eq. 42 far inside the scenario's 1e-4 (a few 1e-9).
    assert!(number_after(&svg, "max relative error ") < 1e-7);
    // |K| is symmetric about the direction opposite the neutral point D1* (FINDINGS.md: 1.2373).
    assert!((number_after(&svg, "theta1 = ") - 1.2373).abs() < 1e-4);
    // K does not grow with L3 everywhere: next to theta1 = pi it falls while L3 < e(theta1).D1*,
    // which is at most -D1*.x = 0.4286 m (FINDINGS.md).
    assert!((number_after(&svg, "it falls first, up to L3 = ") - 0.43).abs() < 0.02);
    // Eq. 47 as printed is the stiffness of the maximum on most of the map (eta1 > 0).
    assert!((number_after(&svg, "is the maximum): ") - 96.2).abs() < 0.5);
}

#[test]
fn ji2014_fig8_maps_the_stiffness_over_the_cartesian_workspace() {
    let (_, svg) = draw("ji2014-fig8");
    for text in ["x [m]", "y [m]", "K [N m/rad]", "It does in 145 of 145 columns", "(0 points; tolerance 1e-4)"] {
        assert!(svg.contains(text), "the SVG has '{text}'");
    }
    assert!(number_after(&svg, "max relative error ") < 1e-7);
    // The paper's "approximately symmetric about x = 0": K(x, y) and K(-x, y) differ by 23 %.
    assert!((number_after(&svg, "differ by up to ") - 23.0).abs() < 1.5);
}

#[test]
fn mohr2011_fig4_shows_the_slices_and_the_dynamics_verdict() {
    let (_, svg) = draw("mohr2011-fig4");
    for text in ["x [m]", "y [m]", "kinematic workspace (Eq. 17-18, z &gt; 0)", "base triangle A1A2A3"] {
        assert!(svg.contains(text), "the SVG has '{text}'");
    }
    // The slice z = 3 m is Fig. 5's: kinematic 31.0 m^2, static 27.2 m^2, every point agrees.
    assert!(svg.contains("z = 3 m: kinematic 31.0 m^2 (static 27.2 m^2); dynamics agree 100 %"));
    // 9 x 9 points per slice at z = 1-5 m: 188 can be assembled, and all 188 agree (179 before
    // the legs and cables were projected: nine boundary points were not at rest in the settle
    // time).
    assert_eq!(number_after(&svg, "9 x 9 points per slice: "), 188.0);
    assert_eq!(number_after(&svg, "9 x 9 points per slice: 188 of "), 188.0);
}

#[test]
fn mohr2011_fig6_shows_two_vertical_slices_and_the_dynamics_verdict() {
    let (_, svg) = draw("mohr2011-fig6");
    for text in ["z [m]", "static workspace (Eq. 17-18 and 29-31)", "x = 0: static", "y = 0: static"] {
        assert!(svg.contains(text), "the SVG has '{text}'");
    }
    // The static workspace reaches z = 5.51 m on the Z axis (spheres of radius l_o = 6 m about
    // 2 a_i, |2 a_i| = 2.31 m: sqrt(36 - 2.31^2) = 5.54 m, less half a cell).
    assert!((number_after(&svg, "up to z = ") - 5.51).abs() < 0.03);
    assert_eq!(number_after(&svg, "9 x 9 points per slice: "), 114.0);
    assert_eq!(number_after(&svg, "9 x 9 points per slice: 114 of "), 116.0);
}

#[test]
fn furet2018_fig4_shows_the_aspects_and_where_eq13_differs() {
    let (_, svg) = draw("furet2018-fig4");
    for text in ["theta1 [rad]", "theta2 [rad]", "zero set of Eq. 13 as printed", "two in each (cuspidal)"] {
        assert!(svg.contains(text), "the SVG has '{text}'");
    }
    // The derived det J vanishes on both families; the printed Eq. 13 does not (FINDINGS.md:
    // -0.0859605 on the folded line at theta2 = 0.5 rad).
    assert!(number_after(&svg, "|det J| &lt;= ") < 1e-12);
    assert!((number_after(&svg, "Eq. 13 as printed gives ") + 0.0859605).abs() < 1e-7);
    // Two aspects of about equal size; the printed form has the wrong sign on 5.8 % of them.
    assert!((number_after(&svg, "aspect det J &gt; 0: ") - 50.0).abs() < 0.5);
    assert!((number_after(&svg, "has the other sign (") - 5.8).abs() < 0.2);
    // The non-singular paths of FINDINGS.md between the two solutions of each aspect.
    assert!((number_after(&svg, "smallest |det J| ") - 0.1349).abs() < 1e-4);
}

/// The points of every `<polyline>` of `svg` with a stroke width of 2 (the data's curves), in
/// pixels, in the SVG's order.
fn polylines(svg: &str) -> Vec<Vec<(f64, f64)>> {
    svg.split("<polyline")
        .skip(1)
        .filter(|p| p.split('>').next().is_some_and(|tag| tag.contains("stroke-width=\"2\"")))
        .map(|p| {
            let at = p.find("points=\"").expect("points") + 8;
            let list = &p[at..at + p[at..].find('"').expect("closing quote")];
            list.split_whitespace()
                .map(|xy| {
                    let (x, y) = xy.split_once(',').expect("x,y");
                    (x.parse().expect("x"), y.parse().expect("y"))
                })
                .collect()
        })
        .collect()
}

/// Pearson's correlation of `a` and `b`.
fn correlation(a: &[f64], b: &[f64]) -> f64 {
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    let (ma, mb) = (mean(a), mean(b));
    let cov: f64 = a.iter().zip(b).map(|(x, y)| (x - ma) * (y - mb)).sum();
    let var = |v: &[f64], m: f64| v.iter().map(|x| (x - m).powi(2)).sum::<f64>();
    cov / (var(a, ma) * var(b, mb)).sqrt()
}
