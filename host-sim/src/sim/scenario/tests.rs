//! Tests of scenario files.

use super::parse::unit_direction;
use super::*;
use crate::sim::render::Light;

const BASE: &str = "seed = 1\nduration_s = 10.0\n";

fn err(text: &str) -> String {
    match Scenario::from_toml_str(text) {
        Ok(s) => unreachable!("accepted: {s:?}"),
        Err(e) => e.to_string(),
    }
}

fn with(extra: &str) -> String {
    format!("{BASE}{extra}")
}

#[test]
fn minimal_file_gets_defaults() {
    let s = Scenario::from_toml_str(BASE).unwrap_or_else(|e| unreachable!("{e}"));
    assert_eq!(s, Scenario::new(1, 10.0, Feedforward::OnWithTarget));
    assert_eq!(s.camera.width, 640);
    assert_eq!(s.target.face_hues_deg, [0.0, 120.0, 240.0, 0.0, 120.0, 240.0]);
    assert_eq!(s.robot.motion, MotionKind::Static);
    assert_eq!(s.frame_count(), 303);
}

#[test]
fn validation_errors_name_the_field() {
    assert_eq!(err(&with("[camera]\nwidth = 0\n")), "camera.width: must be in 16..=4096, got 0");
    assert_eq!(err(&with("[robot]\nmotion = \"C\"\n")), "robot.motion: expected \"static\", \"A\" or \"B\", got \"C\"");
    assert_eq!(
        err(&with("[target]\nface_hues_deg = [0, 120, 240, 0, 120]\n")),
        "target.face_hues_deg: expected 6 values, got 5"
    );
    assert!(err(&with("[camera]\nwidht = 640\n")).starts_with("camera.widht: unknown key"));
    assert!(err(&with("colour = 3\n")).starts_with("colour: unknown key"));
    assert!(err(&with("[lens]\nk1 = 0.1\n")).starts_with("lens: unknown key"));
    assert_eq!(err("seed = 1\n"), "duration_s: missing (this key is required)");
    assert_eq!(
        err(&with("[camera]\ncx = 700.0\n")),
        "camera.cx: must be in [0, 640] (inside the image width), got 700"
    );
    assert_eq!(err("seed = 1\nduration_s = 0\n"), "duration_s: must be in (0, 3600], got 0");
    assert_eq!(err("seed = 1\nduration_s = 4000\n"), "duration_s: must be in (0, 3600], got 4000");
    assert_eq!(err("seed = -3\nduration_s = 1\n"), "seed: must be ≥ 0, got -3");
    assert_eq!(
        err(&with("[tracker]\nmethod = \"GA\"\n")),
        "tracker.method: expected one of \"ga\", \"ff\", \"ff+target\", got \"GA\""
    );
    assert_eq!(
        err(&with("[target]\nconveyor_speed_m_s = 0.01\n")),
        "target.conveyor_speed_m_s: must be 0 (off) or in [0.05, 0.3], got 0.01"
    );
    assert_eq!(
        err(&with("[target]\nconveyor_speed_m_s = 0.4\n")),
        "target.conveyor_speed_m_s: must be in [0, 0.3], got 0.4"
    );
    assert_eq!(
        err(&with("[target]\nconveyor_speed_m_s = 0.3\nconveyor_travel_m = 0.2\n")),
        "target.conveyor_accel_m_s2: must be at least 2·speed²/travel = 0.9000 m/s² to reverse within the \
         travel, got 0.5"
    );
    assert_eq!(
        err(&with("[target]\nconveyor_speed_m_s = 0.1\nrandom_amplitude_m = 0.05\n")),
        "target.random_amplitude_m: the block follows one path: set conveyor_speed_m_s or random_amplitude_m to 0"
    );
    assert_eq!(err(&with("[target]\nrandom_omega_rad_s = 0\n")), "target.random_omega_rad_s: must be in (0, 2], got 0");
    assert_eq!(err(&with("[start]\ndelay_s = -0.1\n")), "start.delay_s: must be in [0, 1], got -0.1");
    assert!(err(&with("[start]\ndelay = 0.1\n")).starts_with("start.delay: unknown key"));
    assert!(err(&with("[tracker]\ndelay = 0.1\n")).starts_with("tracker.delay: unknown key"));
    assert_eq!(err(&with("[camera]\nwidth = \"640\"\n")), "camera.width: expected an integer, got a string (\"640\")");
    assert_eq!(err(&with("camera = 3\n")), "camera: expected a table, got an integer (3)");
    assert_eq!(err(&with("[target]\nsize_m = [0.1, -0.2, 0.3]\n")), "target.size_m[1]: must be in (0, 2], got -0.2");
    assert_eq!(err(&with("[target]\ndistance_m = nan\n")), "target.distance_m: must be in (0, 5], got NaN");
    assert!(err(&with("[target]\ndistance_m = 0.1\n")).starts_with("target.distance_m: must exceed"));
    assert_eq!(
        err(&with("[target]\nface_hues_deg = [0, 120, 360, 0, 120, 240]\n")),
        "target.face_hues_deg[2]: must be in [0, 360), got 360"
    );
    let population = |text: &str| Scenario::from_toml_str(&with(text)).map(|s| s.tuning().ga.population).ok();
    assert_eq!(
        err(&with("[tracker]\nga.population = 0\n")),
        "tracker.ga.population: must be at least 2 and at most the compiled capacity"
    );
    assert!(err(&with("[tracker]\nga.population = 65\n")).starts_with("tracker.ga.population: must be at least 2"));
    assert!(err(&with("[tracker]\nga.population = 15\n")).starts_with("tracker.acquire.seed_immigrants: plus"));
    assert_eq!(population("[tracker]\nga.population = 16\n"), Some(16));
    assert!(
        err(&with("[tracker]\nga.population = -1\n"))
            .starts_with("tracker.ga.population: expected a non-negative integer")
    );
    assert_eq!(population("[tracker.ga]\npopulation = 64\n"), Some(64));
    assert!(err("seed = 1\nduration_s = \n").starts_with("TOML syntax error"));
}

#[test]
fn servo_section_is_validated_field_by_field() {
    let ok =
        Scenario::from_toml_str(&with("[servo]\ndesired_t_m = [0, 0, 0.6]\n")).unwrap_or_else(|e| unreachable!("{e}"));
    assert_eq!(ok.servo, Some(ServoSection::new([0.0, 0.0, 0.6])));
    assert_eq!(Scenario::from_toml_str(BASE).map(|s| s.servo).ok(), Some(None));
    assert_eq!(err(&with("[servo]\ngain = 2\n")), "servo.desired_t_m: missing (this key is required)");
    assert_eq!(
        err(&with("[servo]\ndesired_t_m = [0, 0, 0.1]\n")),
        "servo.desired_t_m[2]: must be in (0.2, 3] (in front of the camera), got 0.1"
    );
    assert_eq!(err(&with("[servo]\ndesired_t_m = [0, 0, 0.6]\ngain = 0\n")), "servo.gain: must be in (0, 50], got 0");
    assert_eq!(
        err(&with("[servo]\ndesired_t_m = [0, 0, 0.6]\nmax_speed_m_s = -1\n")),
        "servo.max_speed_m_s: must be in (0, 2], got -1"
    );
    assert_eq!(
        err(&with("[servo]\ndesired_t_m = [0, 0, 0.6]\ndesired_q_xyzw = [0, 0, 0, 2]\n")),
        "servo.desired_q_xyzw: must be a unit quaternion, got norm 2"
    );
    assert_eq!(
        err(&with("[servo]\ndesired_t_m = [0, 0, 0.6]\ndelay_frames = 11\n")),
        "servo.delay_frames: must be in 0..=10, got 11"
    );
    assert!(err(&with("[servo]\ndesired_t_m = [0, 0, 0.6]\ngian = 1\n")).starts_with("servo.gian: unknown key"));
    let mut s = Scenario::new(3, 5.0, Feedforward::On);
    s.servo = Some(ServoSection {
        desired_q_xyzw: Some([0.0, 0.0, 0.0, 1.0]),
        gain: 3.5,
        ..ServoSection::new([0.01, -0.02, 0.55])
    });
    let text = s.to_toml_string().unwrap_or_else(|e| unreachable!("{e}"));
    assert_eq!(Scenario::from_toml_str(&text).unwrap_or_else(|e| unreachable!("{e}\n{text}")), s);
}

#[test]
fn integers_are_accepted_for_floats_but_not_the_reverse() {
    let s = Scenario::from_toml_str(&with("[target]\ndistance_m = 1\n")).unwrap_or_else(|e| unreachable!("{e}"));
    assert_eq!(s.target.distance_m, 1.0);
    assert_eq!(err(&with("[camera]\nsupersample = 2.0\n")), "camera.supersample: expected an integer, got a float (2)");
}

#[test]
fn round_trip_through_toml() {
    let mut s = Scenario::new(7, 12.5, Feedforward::OnWithTarget);
    s.frame_period_s = 0.04;
    s.start.delay_s = 0.05;
    s.tracker.0.ga.mutation_prob = 0.7;
    s.target.conveyor_speed_m_s = 0.2;
    s.target.conveyor_accel_m_s2 = 0.8;
    s.camera.width = 320;
    s.camera.cx = 161.5;
    s.camera.noise_std = 0.0;
    s.target.size_m = [0.08, 0.12, 0.3];
    s.target.face_hues_deg = [10.0, 50.0, 90.0, 130.0, 200.0, 300.5];
    s.robot = RobotConfig { motion: MotionKind::B, omega_rad_s: 0.3, amplitude_m: 0.05, amplitude_deg: 10.0 };
    let text = s.to_toml_string().unwrap_or_else(|e| unreachable!("{e}"));
    let back = Scenario::from_toml_str(&text).unwrap_or_else(|e| unreachable!("{e}\n{text}"));
    assert_eq!(back, s);
    let json = serde_json::to_value(s).unwrap_or_else(|e| unreachable!("{e}"));
    assert_eq!(json["robot"]["motion"], "B");
    assert_eq!(json["tracker"]["method"], "ff+target");
    assert_eq!(json["tracker"]["ga.mutation_prob"], 0.7);
    assert_eq!(json["start"]["delay_s"], 0.05);
}

#[test]
fn load_names_the_file() {
    let dir = std::env::temp_dir().join(format!("evorec-scenario-test-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap_or_else(|e| unreachable!("{e}"));
    let path = dir.join("bad.toml");
    std::fs::write(&path, with("[camera]\nwidth = 0\n")).unwrap_or_else(|e| unreachable!("{e}"));
    let e = Scenario::load(&path).err().unwrap_or_else(|| unreachable!());
    assert_eq!(e.field(), Some("camera.width"));
    assert!(e.to_string().ends_with("bad.toml: camera.width: must be in 16..=4096, got 0"), "{e}");
    let _ = std::fs::remove_dir_all(&dir);
    assert!(matches!(Scenario::load(dir.join("missing.toml")), Err(ScenarioError::Io { .. })));
}

#[test]
fn every_shipped_scenario_loads() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenarios");
    let mut names = Vec::new();
    for entry in std::fs::read_dir(&dir).unwrap_or_else(|e| unreachable!("{e}")) {
        let path = entry.unwrap_or_else(|e| unreachable!("{e}")).path();
        if path.extension().is_some_and(|e| e == "toml") {
            let s = Scenario::load(&path).unwrap_or_else(|e| unreachable!("{e}"));
            assert!(s.duration_s > 0.0);
            names.push(path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default());
        }
    }
    names.sort();
    for want in
        ["motion_a_ff.toml", "motion_a_ga.toml", "motion_b_ff.toml", "motion_b_ga.toml", "smoke.toml", "static.toml"]
    {
        assert!(names.iter().any(|n| n == want), "{want} missing from {names:?}");
    }
}

#[test]
fn shipped_scenarios_have_the_specified_settings() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenarios");
    let load = |n: &str| Scenario::load(dir.join(n)).unwrap_or_else(|e| unreachable!("{e}"));
    for (file, motion, method) in [
        ("motion_a_ff.toml", MotionKind::A, Feedforward::On),
        ("motion_a_ga.toml", MotionKind::A, Feedforward::Off),
        ("motion_b_ff.toml", MotionKind::B, Feedforward::On),
        ("motion_b_ga.toml", MotionKind::B, Feedforward::Off),
    ] {
        let s = load(file);
        assert_eq!((s.robot.motion, s.method(), s.seed, s.duration_s), (motion, method, 1, 72.0), "{file}");
        assert_eq!(s.robot.omega_rad_s, 0.125, "{file}");
    }
    let smoke = load("smoke.toml");
    assert_eq!(
        (smoke.robot.motion, smoke.robot.omega_rad_s, smoke.method(), smoke.duration_s),
        (MotionKind::A, 0.5, Feedforward::On, 3.0)
    );
    assert_eq!(load("static.toml").robot.motion, MotionKind::Static);
}

#[test]
fn the_tracker_table_tunes_the_tracker_and_names_bad_fields() {
    use evorec_core::target_motion::TargetFilterParams;
    let s = Scenario::from_toml_str(&with("[tracker]\ntarget.acceleration_m_s2 = 0.3\ntarget.image_noise_px = 1\n"))
        .unwrap_or_else(|e| unreachable!("{e}"));
    let want = TargetFilterParams { acceleration_m_s2: 0.3, image_noise_px: 1.0, ..TargetFilterParams::DEFAULT };
    assert_eq!(s.tuning().target, want);
    let text = s.to_toml_string().unwrap_or_else(|e| unreachable!("{e}"));
    assert_eq!(Scenario::from_toml_str(&text).unwrap_or_else(|e| unreachable!("{e}\n{text}")), s);
    assert_eq!(
        err(&with("[tracker]\ntarget.image_noise_px = -0.5\n")),
        "tracker.target.image_noise_px: must be finite and positive"
    );
    assert_eq!(
        err(&with("[tracker]\ntarget.acceleration_m_s2 = \"fast\"\n")),
        "tracker.target.acceleration_m_s2: expected a number, got \"fast\""
    );
    assert!(
        err(&with("[tracker]\ntarget.max_speed_m_s = 1e40\n")).starts_with("tracker.target.max_speed_m_s: expected")
    );
    assert!(
        err(&with("[tracker]\ntarget.position_noise_m = 0.001\n"))
            .starts_with("tracker.target.position_noise_m: unknown key")
    );
    assert_eq!(err(&with("tracker = 3\n")), "tracker: expected a table, got an integer (3)");
}

#[test]
fn the_old_places_of_the_tuning_name_the_new_one() {
    assert_eq!(err(&with("method = \"ff\"\n")), "method: moved to [tracker] method");
    assert_eq!(err(&with("[ga]\npopulation = 40\n")), "ga: moved to [tracker] ga.* (e.g. ga.population)");
    assert!(err(&with("[target_filter]\nmax_gap_s = 0.3\n")).starts_with("target_filter: moved to [tracker] target.*"));
    assert_eq!(err(&with("[tracker]\ndelay_s = 0.1\n")), "tracker.delay_s: moved to [start] delay_s");
    assert_eq!(err(&with("[tracker]\ninitial = \"unknown\"\n")), "tracker.initial: moved to [start] initial");
}

#[test]
fn a_configuration_file_holds_the_tracker_table_alone() {
    let t = TrackerTable::from_toml_str("[tracker]\ntarget.image_noise_px = 0.75\n", Tuning::DEFAULT)
        .unwrap_or_else(|e| unreachable!("{e}"));
    assert_eq!(t.0.target.image_noise_px, 0.75);
    assert_eq!(t.0.target.max_speed_m_s, Tuning::DEFAULT.target.max_speed_m_s);
    let missing = std::env::temp_dir().join("evorec-no-such-config.toml");
    let e = TrackerTable::load(&missing, Tuning::DEFAULT).err().map(|e| e.to_string()).unwrap_or_default();
    assert!(e.contains("evorec-no-such-config.toml"), "{e}");
    let dir = std::env::temp_dir().join(format!("evorec-config-test-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap_or_else(|e| unreachable!("{e}"));
    let bad = dir.join("bad.toml");
    std::fs::write(&bad, "[tracker]\nga.mutaton_prob = 0.5\n").unwrap_or_else(|e| unreachable!("{e}"));
    let e = TrackerTable::load(&bad, Tuning::DEFAULT).err().map(|e| e.to_string()).unwrap_or_default();
    assert!(e.contains("bad.toml") && e.contains("tracker.ga.mutaton_prob: unknown key"), "{e}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn conveyor_direction_frame_and_start_are_read_and_checked() {
    let s = Scenario::from_toml_str(&with(
        "[target]\nconveyor_speed_m_s = 0.1\nconveyor_direction = [0, 0, -2]\nconveyor_direction_frame = \
         \"camera\"\nconveyor_start = \"moving\"\n",
    ))
    .unwrap_or_else(|e| unreachable!("{e}"));
    assert_eq!(s.target.conveyor_direction, [0.0, 0.0, -1.0], "normalised on load");
    assert_eq!(s.target.conveyor_direction_frame, ConveyorFrame::Camera);
    assert_eq!(s.target.conveyor_start, ConveyorStart::Moving);
    let s = Scenario::from_toml_str(&with(
        "[target]\nconveyor_direction = [3, 4, 0]\nconveyor_direction_frame = \"world\"\nconveyor_start = \"rest\"\n",
    ))
    .unwrap_or_else(|e| unreachable!("{e}"));
    assert_eq!(s.target.conveyor_direction, [0.6, 0.8, 0.0]);
    assert_eq!(
        (s.target.conveyor_direction_frame, s.target.conveyor_start),
        (ConveyorFrame::World, ConveyorStart::Rest)
    );
    // Tiny and huge vectors normalise without under- or overflow.
    for text in ["[1e-200, 0, 1e-200]", "[1e300, 0, 1e300]"] {
        let s = Scenario::from_toml_str(&with(&format!("[target]\nconveyor_direction = {text}\n")))
            .unwrap_or_else(|e| unreachable!("{text}: {e}"));
        let d = s.target.conveyor_direction;
        assert!((d[0] - std::f64::consts::FRAC_1_SQRT_2).abs() < 1e-15 && d[0] == d[2] && d[1] == 0.0, "{d:?}");
    }
    // Absent: world y, at rest (today's conveyor).
    let d = Scenario::from_toml_str(BASE).unwrap_or_else(|e| unreachable!("{e}")).target;
    assert_eq!(
        (d.conveyor_direction, d.conveyor_direction_frame, d.conveyor_start),
        (WORLD_Y, ConveyorFrame::World, ConveyorStart::Rest)
    );

    assert_eq!(
        err(&with("[target]\nconveyor_direction = [0, 0, 0]\n")),
        "target.conveyor_direction: must be a finite, non-zero vector, got [0, 0, 0]"
    );
    assert_eq!(
        err(&with("[target]\nconveyor_direction = [1, nan, 0]\n")),
        "target.conveyor_direction: must be a finite, non-zero vector, got [1, NaN, 0]"
    );
    assert_eq!(
        err(&with("[target]\nconveyor_direction = [inf, 0, 0]\n")),
        "target.conveyor_direction: must be a finite, non-zero vector, got [inf, 0, 0]"
    );
    assert_eq!(
        err(&with("[target]\nconveyor_direction = [1, 0]\n")),
        "target.conveyor_direction: expected 3 values, got 2"
    );
    assert_eq!(
        err(&with("[target]\nconveyor_direction = [1, \"up\", 0]\n")),
        "target.conveyor_direction[1]: expected a number, got a string (\"up\")"
    );
    assert_eq!(
        err(&with("[target]\nconveyor_direction_frame = \"flange\"\n")),
        "target.conveyor_direction_frame: expected \"world\" or \"camera\", got \"flange\""
    );
    assert_eq!(
        err(&with("[target]\nconveyor_direction_frame = 1\n")),
        "target.conveyor_direction_frame: expected a string, got an integer (1)"
    );
    assert_eq!(
        err(&with("[target]\nconveyor_start = \"middle\"\n")),
        "target.conveyor_start: expected \"rest\" or \"moving\", got \"middle\""
    );
    assert!(err(&with("[target]\nconveyor_dir = [1, 0, 0]\n")).starts_with("target.conveyor_dir: unknown key"));
}

#[test]
fn conveyor_keys_round_trip_and_are_written_only_when_not_default() {
    // Defaults: nothing written, so the outputs of older scenarios stay as they were.
    let mut s = Scenario::new(2, 8.0, Feedforward::OnWithTarget);
    s.target.conveyor_speed_m_s = 0.1;
    let text = s.to_toml_string().unwrap_or_else(|e| unreachable!("{e}"));
    assert!(!text.contains("conveyor_direction") && !text.contains("conveyor_start"), "{text}");
    let json = serde_json::to_string(&s).unwrap_or_else(|e| unreachable!("{e}"));
    assert!(!json.contains("conveyor_direction") && !json.contains("conveyor_start"), "{json}");
    // Set: written, and read back bit for bit, also for directions normalised on load.
    s.target.conveyor_direction_frame = ConveyorFrame::Camera;
    s.target.conveyor_start = ConveyorStart::Moving;
    let mut x = 0x2545_F491_4F6C_DD1D_u64;
    for k in 0..200 {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        let raw: [f64; 3] = core::array::from_fn(|i| ((x >> (20 * i)) & 0xF_FFFF) as f64 / 524_288.0 - 1.0 + 1e-3);
        let Some(d) = unit_direction(raw) else { unreachable!("{raw:?}") };
        s.target.conveyor_direction = d;
        if k == 0 {
            s.target.conveyor_direction = [0.0, 0.0, -1.0];
        }
        let text = s.to_toml_string().unwrap_or_else(|e| unreachable!("{e}"));
        assert!(k > 0 || text.contains("conveyor_direction = [0.0, 0.0, -1.0]"), "{text}");
        assert!(text.contains("conveyor_direction_frame = \"camera\"") && text.contains("conveyor_start = \"moving\""));
        assert_eq!(Scenario::from_toml_str(&text).unwrap_or_else(|e| unreachable!("{e}\n{text}")), s, "{raw:?}");
    }
    let json = serde_json::to_value(s).unwrap_or_else(|e| unreachable!("{e}"));
    assert_eq!(json["target"]["conveyor_start"], "moving");
    assert_eq!(json["target"]["conveyor_direction_frame"], "camera");
}

#[test]
fn the_render_table_is_read_and_names_bad_fields() {
    assert_eq!(Scenario::from_toml_str(BASE).unwrap_or_else(|e| unreachable!("{e}")).render, Light::default());
    let bad = [
        ("jpeg_quality = 101", "render.jpeg_quality: must be in 0..=100, got 101"),
        ("tone_curve = \"log\"", "render.tone_curve: expected \"linear\", \"srgb\" or \"filmic\", got \"log\""),
        ("white_balance = [1.0, 0.0, 1.0]", "render.white_balance[1]: must be in (0, 4], got 0"),
        ("exposure_s = 0.05", "render.exposure_s: must be in [0, 0.033], got 0.05"),
        ("shadow_normal = [0, 0, 0]", "render.shadow_normal: must be a finite, non-zero vector, got [0, 0, 0]"),
        ("shadow_frame = \"world\"", "render.shadow_frame: expected \"camera\" or \"block\", got \"world\""),
        ("albedo_saturation = 0", "render.albedo_saturation: must be in (0, 1], got 0"),
        ("blur_samples = 0", "render.blur_samples: must be in 1..=32, got 0"),
        ("specular = -1", "render.specular: must be in [0, 4], got -1"),
    ];
    for (line, want) in bad {
        assert_eq!(err(&with(&format!("[render]\n{line}\n"))), want);
    }
    assert!(err(&with("[render]\nglare = 1\n")).starts_with("render.glare: unknown key"));
}

#[test]
fn the_camera_like_scenario_round_trips_and_its_light_file_matches() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenarios");
    let s = Scenario::load(dir.join("camera_like.toml")).unwrap_or_else(|e| unreachable!("{e}"));
    assert!(!s.render.is_default());
    let text = s.to_toml_string().unwrap_or_else(|e| unreachable!("{e}"));
    assert_eq!(Scenario::from_toml_str(&text).unwrap_or_else(|e| unreachable!("{e}\n{text}")), s);
    let light =
        load_light(dir.join("light/camera_like.toml"), s.frame_period_s).unwrap_or_else(|e| unreachable!("{e}"));
    assert_eq!(light, s.render);
    let plain = Scenario::load(dir.join("motion_a_ff.toml")).unwrap_or_else(|e| unreachable!("{e}"));
    assert_eq!(Scenario { render: light, ..plain }, s);
    assert!(!plain.to_toml_string().unwrap_or_default().contains("[render]"));
    let e = light_from_toml_str("[tracker]\nmethod = \"ga\"\n", 0.033).err().map(|e| e.to_string());
    assert_eq!(e.as_deref(), Some("tracker: unknown key (a light file holds a [render] table only)"));
}

#[test]
fn type_errors_name_the_key_and_what_was_given() {
    assert_eq!(err(&with("[camera]\nfx = true\n")), "camera.fx: expected a number, got a boolean (true)");
    assert_eq!(err(&with("[camera]\nfx = 1979-05-27\n")), "camera.fx: expected a number, got a datetime");
    assert_eq!(err(&with("[camera]\nwidth = [1, 2, 3]\n")), "camera.width: expected an integer, got an array");
    assert_eq!(err(&with("[robot]\nmotion = { a = 1 }\n")), "robot.motion: expected a string, got a table");
    assert_eq!(err("seed = 1.5\nduration_s = 1\n"), "seed: expected an integer, got a float (1.5)");
    assert_eq!(err(&with("[start]\ndelay_s = \"x\"\n")), "start.delay_s: expected a number, got a string (\"x\")");
    assert_eq!(
        err(&with("[target]\nsize_m = 1.5\n")),
        "target.size_m: expected an array of 3 numbers, got a float (1.5)"
    );
    assert_eq!(
        err(&with("[servo]\ndesired_t_m = [0, 0, 0.6]\ndesired_q_xyzw = [0, 0, 0]\n")),
        "servo.desired_q_xyzw: expected 4 values, got 3"
    );
    assert_eq!(
        err(&with("[render]\nwhite_balance = [1, true, 1]\n")),
        "render.white_balance[1]: expected a number, got a boolean (true)"
    );
    for table in ["camera", "target", "robot", "servo", "start", "render"] {
        assert_eq!(err(&with(&format!("{table} = [1, 2]\n"))), format!("{table}: expected a table, got an array"));
        assert_eq!(
            err(&with(&format!("{table} = 1979-05-27\n"))),
            format!("{table}: expected a table, got a datetime")
        );
    }
    assert_eq!(err(&with("tracker = [1]\n")), "tracker: expected a table, got an array");
}

#[test]
fn unknown_keys_list_the_table_s_keys() {
    assert_eq!(err(&with("[start]\ndelay = 0.1\n")), "start.delay: unknown key (expected one of: initial, delay_s)");
    assert_eq!(
        err(&with("[camera]\nwidht = 640\n")),
        "camera.widht: unknown key (expected one of: width, height, fx, fy, cx, cy, baseline_m, noise_std, \
         supersample)"
    );
    assert_eq!(
        err(&with("colour = 3\n")),
        "colour: unknown key (expected one of: seed, duration_s, frame_period_s, method, camera, target, robot, ga, \
         start, tracker, occlusion, servo, target_filter, render)"
    );
    assert_eq!(
        err(&with("[robot]\nspeed = 1\n")),
        "robot.speed: unknown key (expected one of: motion, omega_rad_s, amplitude_m, amplitude_deg)"
    );
    assert_eq!(
        err(&with("camera.widht = 640\n")),
        "camera.widht: unknown key (expected one of: width, height, fx, fy, cx, cy, baseline_m, noise_std, \
         supersample)"
    );
}

#[test]
fn range_and_consistency_errors_without_other_tests() {
    assert_eq!(err("duration_s = 1\n"), "seed: missing (this key is required)");
    assert_eq!(err("seed = 1\nduration_s = 10\nframe_period_s = 2\n"), "frame_period_s: must be in [0.001, 1], got 2");
    assert_eq!(
        err("seed = 1\nduration_s = 0.5\nframe_period_s = 0.6\n"),
        "frame_period_s: must not exceed duration_s (0.5), got 0.6"
    );
    assert_eq!(err(&with("[camera]\ncy = 500\n")), "camera.cy: must be in [0, 480] (inside the image height), got 500");
    assert_eq!(err(&with("[camera]\nbaseline_m = 2\n")), "camera.baseline_m: must be in (0, 1], got 2");
    assert_eq!(err(&with("[camera]\nsupersample = 9\n")), "camera.supersample: must be in 1..=8, got 9");
    assert_eq!(
        err(&with("[camera]\nwidth = 4096\nheight = 4096\ncx = 2048\ncy = 2048\nsupersample = 3\n")),
        "camera.supersample: width·height·supersample² must be ≤ 67108864, got 150994944"
    );
    assert!(Scenario::from_toml_str(&with("[camera]\nwidth = 4096\nheight = 4096\nsupersample = 2\n")).is_ok());
    assert_eq!(
        err(&with("[target]\ndistance_m = 0.1\n")),
        "target.distance_m: must exceed the block's half diagonal plus 0.05 m (0.1846 m), got 0.1"
    );
    assert_eq!(err(&with("[target]\nyaw0_deg = 255\n")), "target.yaw0_deg: must be in [-180, 180], got 255");
    assert_eq!(err(&with("[target]\nconveyor_dwell_s = 61\n")), "target.conveyor_dwell_s: must be in [0, 60], got 61");
    assert_eq!(
        err(&with("[target]\nplacement = \"anywhere\"\n")),
        "target.placement: expected \"fixed\" or \"random\", got \"anywhere\""
    );
    assert_eq!(err(&with("[robot]\namplitude_m = 0.5\n")), "robot.amplitude_m: must be in [0, 0.3], got 0.5");
    assert_eq!(
        err(&with("[servo]\ndesired_t_m = [2, 0, 0.6]\n")),
        "servo.desired_t_m[0]: must be in [0, 1] (|x|), got 2"
    );
    assert_eq!(
        err(&with("[servo]\ndesired_t_m = [0, -2, 0.6]\n")),
        "servo.desired_t_m[1]: must be in [0, 1] (|y|), got 2"
    );
    assert_eq!(err(&with("[start]\ninitial = 1\n")), "start.initial: expected \"truth\" or \"unknown\", got 1");
    assert_eq!(
        light_from_toml_str("render = 3\n", 0.033).err().map(|e| e.to_string()).as_deref(),
        Some("render: expected a table")
    );
    assert_eq!(
        light_from_toml_str("[render]\nglare = 1\n", 0.033).err().map(|e| e.to_string()).as_deref(),
        Some(
            "render.glare: unknown key (expected one of: light_dir_cam, ambient, diffuse, albedo_saturation, \
             specular, shininess, shadow_frame, shadow_normal, shadow_offset_m, shadow_width_m, tone_curve, \
             tone_exposure, white_balance, chroma_noise_std, exposure_s, blur_samples, jpeg_quality)"
        )
    );
}

#[test]
fn the_status_counts_old_names_are_read_in_a_scenario() {
    let status = |text: &str| Scenario::from_toml_str(&with(text)).map(|s| s.tuning().status);
    let old = status("[tracker]\nstatus.confirm_generations = 4\nstatus.lose_generations = 2\n")
        .unwrap_or_else(|e| unreachable!("{e}"));
    let new = status("[tracker.status]\nconfirm_frames = 4\nlose_frames = 2\n").unwrap_or_else(|e| unreachable!("{e}"));
    assert_eq!(old, new);
    assert_eq!(
        err(&with("[tracker.status]\nlost_frames_to_search = 50\nlost_generations_to_search = 50\n")),
        "tracker.status.lost_generations_to_search: is the old name of tracker.status.lost_frames_to_search: give \
         one of them"
    );
}

#[test]
fn the_light_parts_make_up_shading_wb() {
    // The four parts of `light/shading_wb.toml` (docs/method.md measures each alone): every part
    // a light of its own, no key in two parts, and together the whole light.
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenarios/light");
    let table = |name: &str| -> toml::Table {
        let text = std::fs::read_to_string(dir.join(name)).unwrap_or_else(|e| unreachable!("{name}: {e}"));
        let mut t: toml::Table = text.parse().unwrap_or_else(|e| unreachable!("{name}: {e}"));
        match t.remove("render") {
            Some(toml::Value::Table(render)) if t.is_empty() => render,
            other => unreachable!("{name}: a [render] table only, got {other:?}"),
        }
    };
    let mut union = toml::Table::new();
    for part in ["shading.toml", "paint.toml", "tone_curve.toml", "white_balance.toml"] {
        let light = load_light(dir.join(part), 0.033).unwrap_or_else(|e| unreachable!("{part}: {e}"));
        assert!(!light.is_default(), "{part}");
        for (key, value) in table(part) {
            assert!(union.insert(key.clone(), value).is_none(), "{part}: {key} is in another part too");
        }
    }
    assert_eq!(union, table("shading_wb.toml"));
    let whole = light_from_toml_str(
        &toml::to_string(&toml::Table::from_iter([("render".to_owned(), union.into())]))
            .unwrap_or_else(|e| unreachable!("{e}")),
        0.033,
    )
    .unwrap_or_else(|e| unreachable!("the parts together: {e}"));
    let shading_wb = load_light(dir.join("shading_wb.toml"), 0.033).unwrap_or_else(|e| unreachable!("{e}"));
    assert_eq!(whole, shading_wb);
}
