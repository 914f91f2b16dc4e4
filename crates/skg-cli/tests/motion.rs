//! Pictures of the motion: `plot path` and `animate` from a real solve, with the scene
//! found through summary.json; the GIF's frames and the strip's size are what was asked;
//! bad requests are clear errors. (The curves drawn are tested against closed forms in
//! skg-plot's `motion` module.)

mod common;

use std::path::Path;

fn solve_into(scene: &str, dir: &Path) {
    let o = common::skg(&[common::scenario(scene).to_str().unwrap(), "-o", dir.to_str().unwrap(), "-q"], Path::new("."));
    assert!(o.status.success(), "{}", common::text(&o));
}

/// Width and height of a PNG, from its IHDR chunk.
fn png_size(path: &Path) -> (u32, u32) {
    let b = std::fs::read(path).unwrap();
    assert_eq!(&b[..8], b"\x89PNG\r\n\x1a\n");
    (u32::from_be_bytes(b[16..20].try_into().unwrap()), u32::from_be_bytes(b[20..24].try_into().unwrap()))
}

#[test]
fn path_picture_and_animation_of_a_solve() {
    let dir = tempfile::tempdir().unwrap();
    let sol = dir.path().join("tumbler");
    solve_into("tumbler", &sol);
    let summary: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(sol.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["scene_file"], common::scenario("tumbler").to_str().unwrap());
    let s = |p: &Path| p.to_str().unwrap().to_string();

    let stem = dir.path().join("img/path");
    let o = common::skg(&["plot", "path", &s(&sol), "-o", &s(&stem)], Path::new("."));
    assert!(o.status.success(), "{}", common::text(&o));
    let svg = std::fs::read_to_string(stem.with_extension("svg")).unwrap();
    for needle in ["wall drum (h = 0)", "reference (time stepping)", "in contact", "y against x"] {
        assert!(svg.contains(needle), "`{needle}` not in the SVG");
    }
    assert_eq!(png_size(&stem.with_extension("png")), skg_plot::motion::PATH_SIZE);

    let gif_path = dir.path().join("img/tumbler.gif");
    let o = common::skg(
        &["animate", &s(&sol), "-o", &s(&gif_path), "--frames", "12", "--fps", "10", "--size", "320x240", "-q"],
        Path::new("."),
    );
    assert!(o.status.success(), "{}", common::text(&o));
    let mut opts = gif::DecodeOptions::new();
    opts.set_color_output(gif::ColorOutput::Indexed);
    let mut decoder = opts.read_info(std::fs::File::open(&gif_path).unwrap()).unwrap();
    assert_eq!((decoder.width(), decoder.height()), (320, 240));
    let mut frames = 0;
    while let Some(f) = decoder.read_next_frame().unwrap() {
        assert_eq!(f.delay, 10, "1/10 s per frame, in hundredths");
        frames += 1;
    }
    assert_eq!(frames, 12);
    // no temporary file is left beside it
    let names: Vec<String> =
        std::fs::read_dir(dir.path().join("img")).unwrap().map(|e| e.unwrap().file_name().into_string().unwrap()).collect();
    assert!(names.iter().all(|n| !n.contains("tmp")), "{names:?}");

    let strip = dir.path().join("img/strip.png");
    let o = common::skg(&["animate", &s(&sol), "-o", &s(&strip), "--strip", "4", "--size", "200x180"], Path::new("."));
    assert!(o.status.success(), "{}", common::text(&o));
    assert_eq!(png_size(&strip), (800, 180));
}

#[test]
fn axes_can_be_time_and_velocities() {
    let dir = tempfile::tempdir().unwrap();
    let sol = dir.path().join("plate");
    solve_into("vibrating_plate", &sol);
    let stem = dir.path().join("plate");
    let o = common::skg(&["plot", "path", sol.to_str().unwrap(), "-o", stem.to_str().unwrap()], Path::new("."));
    assert!(o.status.success(), "{}", common::text(&o));
    assert!(std::fs::read_to_string(stem.with_extension("svg")).unwrap().contains("wall plate (h = 0)"));
    let o = common::skg(&["plot", "path", sol.to_str().unwrap(), "--x", "y", "--y", "y_dot", "-o", stem.to_str().unwrap()], Path::new("."));
    assert!(o.status.success(), "{}", common::text(&o));
    assert!(!std::fs::read_to_string(stem.with_extension("svg")).unwrap().contains("wall plate"));
}

#[test]
fn bad_requests_are_clear_errors() {
    let dir = tempfile::tempdir().unwrap();
    let sol = dir.path().join("ff");
    solve_into("free_fall", &sol);
    let s = sol.to_str().unwrap();
    let out = dir.path().join("x");
    let o = common::skg(&["plot", "path", s, "--y", "nope", "-o", out.to_str().unwrap()], Path::new("."));
    assert_eq!(o.status.code(), Some(1));
    assert!(common::text(&o).contains("no column `nope` in the trajectory (columns: t, x, x_dot, energy)"), "{}", common::text(&o));
    let o = common::skg(&["animate", s, "-o", dir.path().join("a.avi").to_str().unwrap()], Path::new("."));
    assert_eq!(o.status.code(), Some(1));
    assert!(common::text(&o).contains(".gif, .mp4 or .png"), "{}", common::text(&o));
    // a scene that does not describe the solution
    let o = common::skg(
        &["plot", "path", s, "--scene", common::scenario("tumbler").to_str().unwrap(), "-o", out.to_str().unwrap()],
        Path::new("."),
    );
    assert_eq!(o.status.code(), Some(1));
    assert!(common::text(&o).contains("does not describe this trajectory"), "{}", common::text(&o));
    // without summary.json, the scene must be named
    std::fs::remove_file(sol.join("summary.json")).unwrap();
    let o = common::skg(&["plot", "path", s, "-o", out.to_str().unwrap()], Path::new("."));
    assert_eq!(o.status.code(), Some(1));
    assert!(common::text(&o).contains("--scene"), "{}", common::text(&o));
    let o = common::skg(&["animate", s, "--size", "10x10", "-o", dir.path().join("a.gif").to_str().unwrap()], Path::new("."));
    assert_eq!(o.status.code(), Some(2));
    // an MP4 needs ffmpeg: without it, the message says so
    if std::process::Command::new("ffmpeg").arg("-version").output().is_err() {
        let sol = dir.path().join("ff2");
        solve_into("free_fall", &sol);
        let o = common::skg(&["animate", sol.to_str().unwrap(), "-o", dir.path().join("a.mp4").to_str().unwrap(), "-q"], Path::new("."));
        assert_eq!(o.status.code(), Some(1));
        assert!(common::text(&o).contains("needs ffmpeg"), "{}", common::text(&o));
        assert!(!dir.path().join("a.mp4").exists());
    }
}

#[test]
fn gallery_page_with_pictures_and_errors() {
    let dir = tempfile::tempdir().unwrap();
    let page = dir.path().join("docs/gallery.md");
    let o = common::skg(
        &[
            "gallery",
            common::scenario("free_fall").to_str().unwrap(),
            common::scenario("vibrating_plate").to_str().unwrap(),
            "-o",
            page.to_str().unwrap(),
            "-q",
            "--strip",
            "3",
        ],
        Path::new("."),
    );
    assert!(o.status.success(), "{}", common::text(&o));
    let text = std::fs::read_to_string(&page).unwrap();
    // free fall is exact to round-off on SBP242: its error is printed as such
    let row = text.lines().find(|l| l.starts_with("| [free fall](#free-fall)")).unwrap();
    assert!(row.contains("| 32 SBP242 | global | passed |"), "{row}");
    let error: f64 = row.split('|').nth(5).and_then(|c| c.split_whitespace().next()).and_then(|e| e.parse().ok()).expect(row);
    assert!(error < 1e-12, "free fall's error {error:e} is round-off: {row}");
    assert!(text.contains("## vibrating plate") && text.contains("![vibrating plate frames](img/gallery/vibrating_plate_frames.png)"));
    for stem in ["free_fall", "vibrating_plate"] {
        let img = dir.path().join("docs/img/gallery");
        assert_eq!(png_size(&img.join(format!("{stem}.png"))), (720, 560));
        assert_eq!(png_size(&img.join(format!("{stem}_frames.png"))), (3 * 260, 230));
    }
    // while another process holds the pictures' directory, a second gallery is refused
    let lock = std::fs::File::create(dir.path().join("docs/img/gallery/.skg-lock")).unwrap();
    lock.try_lock().unwrap();
    let o = common::skg(&["gallery", common::scenario("free_fall").to_str().unwrap(), "-o", page.to_str().unwrap(), "-q"], Path::new("."));
    assert_eq!(o.status.code(), Some(1));
    assert!(common::text(&o).contains("another skg-solve is writing into"), "{}", common::text(&o));
    assert_eq!(std::fs::read_to_string(&page).unwrap(), text, "the page is left as it was");
}
