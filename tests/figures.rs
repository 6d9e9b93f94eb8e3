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
