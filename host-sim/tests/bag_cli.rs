//! `evorec import` and `evorec track BAG` on bad bags: one `error: …` line naming the topic,
//! message or key, exit status 1, and nothing at `--out` — except for a bag that cannot be
//! read to its end (truncated or corrupt), whose frames before that point are tracked and
//! written. The bags are written by the test
//! from an exported simulator scenario (`evorec_sim::rig::bag::testbag`), then spoiled.

use std::path::{Path, PathBuf};

use evorec_sim::recording::sequence::Sequence;
use evorec_sim::rig::bag::testbag::{self, TestBag, Transforms};
use evorec_sim::rig::export;

/// A short exported scenario (1 s of 160x120 frames).
mod common;
#[path = "bag_cli/results.rs"]
mod results;
use common::{evorec, evorec_env};

fn scratch(name: &str) -> PathBuf {
    common::scratch("bag-cli", name)
}

fn sequence(dir: &Path) -> Sequence {
    let s = evorec_sim::sim::scenario::fixture::hil_motion_a_ff(1.0);
    export::export(&s, "short", &dir.join("seq"), None).unwrap_or_else(|e| panic!("{e:#}"));
    Sequence::load(&dir.join("seq")).unwrap_or_else(|e| panic!("{e}"))
}

fn path_str(p: &Path) -> &str {
    p.to_str().unwrap_or_else(|| panic!("non-UTF-8 path {}", p.display()))
}

/// A scratch directory with the short sequence and its rig file.
fn setup(name: &str) -> (PathBuf, Sequence, PathBuf) {
    let dir = scratch(name);
    let seq = sequence(&dir);
    let rig = dir.join("rig.toml");
    std::fs::write(&rig, testbag::rig_toml(&seq)).expect("rig");
    (dir, seq, rig)
}

/// The one line a failed run printed on stderr (exit status 1), holding every one of `needles`.
fn one_error_line(cmd: &str, o: &std::process::Output, needles: &[&str]) {
    assert_eq!(o.status.code(), Some(1), "{cmd}: {o:?}");
    let stderr = String::from_utf8_lossy(&o.stderr);
    let lines: Vec<&str> = stderr.lines().collect();
    assert_eq!(lines.len(), 1, "{cmd}: expected one line on stderr, got:\n{stderr}");
    assert!(lines[0].starts_with("error: "), "{}", lines[0]);
    for n in needles {
        assert!(lines[0].contains(n), "{cmd}: '{n}' not in: {}", lines[0]);
    }
}

/// Runs `evorec import` and `evorec track` on `bag`; both must fail with one line holding
/// every one of `needles`, and leave nothing at their `--out`.
fn fails(dir: &Path, bag: &Path, rig: &Path, needles: &[&str]) {
    for cmd in ["import", "track"] {
        let out = dir.join(format!("out-{cmd}"));
        let o = evorec(&[cmd, path_str(bag), "--rig", path_str(rig), "--out", path_str(&out)]);
        one_error_line(cmd, &o, needles);
        assert!(!out.exists(), "{cmd} wrote {}", out.display());
        assert!(!dir.join(format!("out-{cmd}.partial")).exists(), "{cmd} left a partial directory");
    }
}

#[test]
fn bad_bags_are_named_and_nothing_is_written() {
    let (dir, seq, rig) = setup("bad");
    let bag = |name: &str, opts: TestBag| {
        let p = dir.join(format!("{name}.mcap"));
        testbag::write(&seq, &p, &opts).unwrap_or_else(|e| panic!("{e:#}"));
        p
    };

    let no_joints = bag("no-joints", TestBag { skip_topics: vec!["/joint_states".into()], ..TestBag::default() });
    fails(&dir, &no_joints, &rig, &["no topic /joint_states", "the bag's topics: ", "/stereo/left/image ("]);

    let silent =
        bag("silent-info", TestBag { silent_topics: vec!["/stereo/right/camera_info".into()], ..TestBag::default() });
    fails(
        &dir,
        &silent,
        &rig,
        &["topic /stereo/right/camera_info (topics.right_info of the rig file) is in the bag but holds no message"],
    );
    let good = bag("good", TestBag::default());
    let bytes = std::fs::read(&good).expect("bag");
    let junk = dir.join("junk.mcap");
    std::fs::write(&junk, &bytes[bytes.len() / 3..bytes.len() / 2]).expect("write");
    fails(&dir, &junk, &rig, &["junk.mcap: not a readable MCAP file (truncated or corrupt) after 0 messages"]);
    let yuv = bag("yuv", TestBag { left_encoding: "yuv422".into(), ..TestBag::default() });
    fails(&dir, &yuv, &rig, &["/stereo/left/image message 0", "unknown encoding \"yuv422\""]);
    let mono = bag("mono", TestBag { right_encoding: "mono8".into(), ..TestBag::default() });
    fails(&dir, &mono, &rig, &["/stereo/right/image message 0", "mono image cannot give hue"]);

    let short = bag("short-joints", TestBag { joints_until_s: Some(0.5), ..TestBag::default() });
    fails(&dir, &short, &rig, &["/stereo/left/image message 16", "outside the joint samples of /joint_states"]);

    let skew = bag("non-rigid", TestBag { transforms: Transforms::NonRigid, ..TestBag::default() });
    fails(&dir, &skew, &rig, &["/tf_static message 0", "right_camera_optical", "not rigid"]);
    let no_left = bag("no-left", TestBag { transforms: Transforms::NoLeft, ..TestBag::default() });
    fails(
        &dir,
        &no_left,
        &rig,
        &["/tf_static", "no transform between 'left_camera_optical' and 'right_camera_optical'"],
    );

    let recalibrated = bag("recalibrated", TestBag { change_left_info_at: Some(7), ..TestBag::default() });
    fails(&dir, &recalibrated, &rig, &["/stereo/left/camera_info message 7", "calibration changed mid-bag"]);

    let bad_rig = dir.join("bad-rig.toml");
    let text = testbag::rig_toml(&seq).replace("[target]\n", "[target]\ncolour = \"red\"\n");
    std::fs::write(&bad_rig, text).expect("rig");
    fails(&dir, &good, &bad_rig, &["bad-rig.toml:", "unknown field `colour`"]);
    let pose = "initial_pose = { t_m = [0.0, 0.0, 0.7], q_xyzw = [0.0, 0.0, 0.0, 2.0] }\n";
    let text =
        testbag::rig_toml(&seq).lines().filter(|l| !l.starts_with("initial_pose")).collect::<Vec<_>>().join("\n");
    std::fs::write(&bad_rig, format!("{text}\n{pose}")).expect("rig");
    fails(&dir, &good, &bad_rig, &["bad-rig.toml: target.initial_pose: q_xyzw must be a unit quaternion"]);
    let _ = std::fs::remove_dir_all(&dir);
}

/// Runs `evorec ARGS --out OUT` on a bag that cannot be read to its end: one error line naming
/// the file and the cut, exit status 1, and the outputs of the frames before the cut written.
fn cut_short(cmd: &str, args: &[&str], out: &Path, needles: &[&str]) {
    let mut all = vec![cmd];
    all.extend_from_slice(args);
    all.extend_from_slice(&["--out", path_str(out), "-q"]);
    let mut needles = needles.to_vec();
    needles.push("not a readable MCAP file (truncated or corrupt) after");
    one_error_line(cmd, &evorec(&all), &needles);
}

/// `--start/--end` keep the frames of the window (times as in the whole run), and
/// `--absolute-stamps` writes them as ROS stamps; the header says which.
fn window_and_stamps(bag: &Path, rig: &Path, whole: &Path, dir: &Path) {
    let header = std::fs::read_to_string(whole.join("estimate.tum")).expect("estimate");
    assert!(header.contains("# t: s since the ROS stamp 1700000000 s (header.stamp = 1700000000 + t"), "{header}");
    let time = |row: &String| row.split(' ').next().and_then(|t| t.parse::<f64>().ok()).expect("time");
    let all: Vec<f64> = rows(&whole.join("estimate.tum")).iter().map(time).collect();
    let (out, args) = (dir.join("window"), ["--start", "0.3", "--end", "1700000000600000000ns", "--absolute-stamps"]);
    let mut cmd = vec!["track", path_str(bag), "--rig", path_str(rig), "--out", path_str(&out), "-q"];
    cmd.extend_from_slice(&args);
    assert!(evorec(&cmd).status.success());
    let text = std::fs::read_to_string(out.join("estimate.tum")).expect("estimate");
    assert!(text.contains("# t: the image's header.stamp (ROS time, s since the epoch)"), "{text}");
    let got: Vec<f64> = rows(&out.join("estimate.tum")).iter().map(|r| time(r) - 1.7e9).collect();
    let want: Vec<f64> = all.iter().copied().filter(|t| *t >= all[0] + 0.3 - 1e-9 && *t <= 0.6 + 1e-9).collect();
    assert_eq!(got.len(), want.len());
    assert!(got.iter().zip(&want).all(|(g, w)| (g - w).abs() < 1e-6), "{got:?} vs {want:?}");
}

/// `evorec rig BAG` drafts the rig file: with the block's section added, it tracks to the same
/// estimate as the hand-written one.
fn drafted_rig_tracks_the_same(bag: &Path, rig: &Path, whole: &Path, dir: &Path) {
    let draft = dir.join("drafted.toml");
    let o = evorec(&["rig", path_str(bag), "--out", path_str(&draft)]);
    assert!(o.status.success(), "{o:?}");
    assert!(String::from_utf8_lossy(&o.stderr).contains("add the block's [target] section"), "{o:?}");
    let text = std::fs::read_to_string(&draft).expect("draft");
    assert!(!text.contains("\"TODO\"") && text.contains("# [target]"), "{text}");
    let hand = std::fs::read_to_string(rig).expect("rig");
    let target = &hand[hand.find("[target]").expect("target")..];
    std::fs::write(&draft, format!("{text}\n{target}")).expect("write");
    let out = dir.join("drafted");
    let o = evorec(&["track", path_str(bag), "--rig", path_str(&draft), "--out", path_str(&out), "-q"]);
    assert!(o.status.success(), "{o:?}");
    let same = std::fs::read(out.join("estimate.tum")).expect("estimate");
    assert_eq!(same, std::fs::read(whole.join("estimate.tum")).expect("estimate"), "estimate.tum differs");
    let again = evorec(&["rig", path_str(bag), "--out", path_str(&draft)]);
    assert_eq!(again.status.code(), Some(1), "overwrote the rig file");
}

/// The estimate's rows (without comments).
fn rows(path: &Path) -> Vec<String> {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    text.lines().filter(|l| !l.starts_with('#')).map(str::to_owned).collect()
}

#[test]
fn a_bag_cut_short_is_tracked_up_to_the_cut() {
    let (dir, seq, rig) = setup("cut");
    let good = dir.join("good.mcap");
    testbag::write(&seq, &good, &TestBag::default()).unwrap_or_else(|e| panic!("{e:#}"));
    let full = dir.join("full");
    let o = evorec(&["track", path_str(&good), "--rig", path_str(&rig), "--out", path_str(&full), "-q"]);
    assert!(o.status.success(), "{o:?}");
    let all = rows(&full.join("estimate.tum"));
    let bytes = std::fs::read(&good).expect("bag");
    let truncated = dir.join("truncated.mcap");
    std::fs::write(&truncated, &bytes[..bytes.len() * 3 / 5]).expect("write");
    let mut spoiled = vec![truncated];
    for (name, compression) in [("corrupt-zstd", Some(mcap::Compression::Zstd)), ("corrupt-plain", None)] {
        let p = dir.join(format!("{name}.mcap"));
        testbag::write(&seq, &p, &TestBag { compression, ..TestBag::default() }).unwrap_or_else(|e| panic!("{e:#}"));
        let mut bytes = std::fs::read(&p).expect("bag");
        let mid = bytes.len() / 2;
        bytes[mid..mid + 64].fill(0xA5);
        std::fs::write(&p, &bytes).expect("write");
        spoiled.push(p);
    }
    for bag in &spoiled {
        let name = bag.file_name().and_then(|n| n.to_str()).unwrap_or_default();
        let (out, seq_out) = (dir.join(format!("out-{name}")), dir.join(format!("seq-{name}")));
        cut_short(
            "track",
            &[path_str(bag), "--rig", path_str(&rig)],
            &out,
            &[name, "tracked the", "\"partial\": true"],
        );
        let summary = std::fs::read_to_string(out.join("summary.json")).expect("summary");
        assert!(summary.contains("\"partial\": true") && summary.contains("\"cut\": "), "{summary}");
        // The frames before the cut are tracked as in the whole bag (the last one's joint
        // velocity may differ: it is one-sided at the cut).
        let some = rows(&out.join("estimate.tum"));
        assert!(some.len() > 2 && some.len() < all.len(), "{name}: {} of {} frames", some.len(), all.len());
        assert_eq!(some[..some.len() - 1], all[..some.len() - 1], "{name}");
        cut_short("import", &[path_str(bag), "--rig", path_str(&rig)], &seq_out, &[name, "imported the"]);
        let imported = Sequence::load(&seq_out).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(imported.frames.len(), some.len(), "{name}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_good_bag_imports_and_tracks_from_the_command_line() {
    let (dir, seq, rig) = setup("good");
    // A bag directory as `ros2 bag record` writes it.
    std::fs::create_dir_all(dir.join("bag")).expect("bag dir");
    testbag::write(&seq, &dir.join("bag/bag_0.mcap"), &TestBag::default()).unwrap_or_else(|e| panic!("{e:#}"));
    std::fs::write(dir.join("bag/metadata.yaml"), "rosbag2_bagfile_information: {}\n").expect("metadata");
    let (bag, out) = (dir.join("bag"), dir.join("tracked"));
    let o = evorec(&["track", path_str(&bag), "--rig", path_str(&rig), "--out", path_str(&out), "-v"]);
    assert!(o.status.success(), "{o:?}");
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(stderr.contains("[INFO ]") && stderr.contains("unpaired: 0 left, 0 right"), "{stderr}");
    for f in ["estimate.tum", "estimate.mcap", "metadata.yaml", "summary.json", "trace.csv"] {
        assert!(out.join(f).is_file(), "{f} missing");
    }
    results::check(&out, &bag.join("bag_0.mcap"), &rig);
    let summary = std::fs::read_to_string(out.join("summary.json")).expect("summary");
    assert!(summary.contains("\"unpaired_left\": 0") && summary.contains("\"joint_velocities\": \"derived\""));
    window_and_stamps(&bag, &rig, &out, &dir);
    drafted_rig_tracks_the_same(&bag, &rig, &out, &dir);
    // Without --rig a bag is recognised and the rig file asked for.
    let o = evorec(&["track", path_str(&bag), "--out", path_str(&dir.join("x")), "-q"]);
    assert!(String::from_utf8_lossy(&o.stderr).contains("give its rig file with --rig"), "{o:?}");
    let o = evorec(&["import", path_str(&bag), "--rig", path_str(&rig), "--out", path_str(&dir.join("seq2")), "-q"]);
    assert!(o.status.success() && o.stderr.is_empty() && o.stdout.is_empty(), "{o:?}");
    // Progress on stderr that is not a terminal: plain lines (here one per frame).
    let lines = dir.join("lines");
    let args = ["track", path_str(&bag), "--rig", path_str(&rig), "--out", path_str(&lines)];
    let o = evorec_env(&args, &[("EVOREC_PROGRESS_SECS", "0")]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(
        o.status.success() && stderr.lines().any(|l| l.contains("frames done, ") && l.contains(" frames/s, ETA ")),
        "{stderr}"
    );
    let o = evorec(&["-q", "track", path_str(&bag), "--rig", path_str(&rig), "--out", path_str(&dir.join("quiet"))]);
    assert!(o.status.success() && o.stderr.is_empty() && o.stdout.is_empty(), "{o:?}");
    assert!(Sequence::load(&dir.join("seq2")).is_ok());
    let _ = std::fs::remove_dir_all(&dir);
}
