use std::format;

use super::*;

fn with(name: &str, value: Value) -> Tuning {
    let mut t = Tuning::DEFAULT;
    t.set(name, value).unwrap();
    t
}

fn field_of(t: &Tuning) -> Option<&'static str> {
    t.validate(64).err().map(|e| e.field)
}

#[test]
fn the_defaults_are_valid_and_every_name_is_unique() {
    assert_eq!(Tuning::DEFAULT.validate(40), Ok(()));
    for (i, f) in FIELDS.iter().enumerate() {
        assert_eq!(field_index(f.name), Some(i), "{} is listed twice", f.name);
        assert!(!f.meaning.is_empty());
    }
}

#[test]
fn every_field_reads_back_what_was_set() {
    for f in &FIELDS {
        let v = match f.kind {
            Kind::Real => Value::Real(0.123),
            Kind::Int => Value::Int(7),
            Kind::Name(names) => Value::Name(names[0]),
        };
        let t = with(f.name, v);
        assert_eq!(t.get(f.name), Some(v), "{}", f.name);
        let changed = FIELDS.iter().filter(|g| (g.get)(&t) != (g.get)(&Tuning::DEFAULT)).count();
        assert!(changed <= 1, "setting {} changed {changed} fields", f.name);
    }
}

#[test]
fn a_bad_value_names_its_field() {
    let e = Tuning::DEFAULT.validate(64);
    assert_eq!(e, Ok(()));
    let t = with("ga.mutation_prob", Value::Real(1.5));
    let e = t.validate(64).unwrap_err();
    assert_eq!(format!("{e}"), "tracker.ga.mutation_prob: must be in [0, 1]");
    assert_eq!(field_of(&with("target.image_noise_px", Value::Real(-0.5))), Some("target.image_noise_px"));
    assert_eq!(field_of(&with("ga.settled_fitness", Value::Real(f32::NAN))), Some("ga.settled_fitness"));
    assert_eq!(field_of(&with("acquire.scan_stride", Value::Int(0))), Some("acquire.scan_stride"));
    assert_eq!(field_of(&with("acquire.spread_m.fine", Value::Real(f32::NAN))), Some("acquire.spread_m.fine"));
    assert_eq!(field_of(&with("status.confirm_frames", Value::Int(0))), Some("status.confirm_frames"));
    assert_eq!(field_of(&with("status.lose_fitness", Value::Real(0.9))), Some("status.lose_fitness"));
    assert_eq!(field_of(&with("hue_tolerance", Value::Int(90))), Some("hue_tolerance"));
    assert_eq!(field_of(&with("max_dt_s", Value::Real(0.0))), Some("max_dt_s"));
    assert_eq!(field_of(&with("ga.level_cdf.medium", Value::Real(0.1))), Some("ga.level_cdf.medium"));
    assert_eq!(field_of(&with("ga.settled_level_cdf.coarse", Value::Real(-0.1))), Some("ga.settled_level_cdf.coarse"));
    assert_eq!(field_of(&with("ga.population", Value::Int(65))), Some("ga.population"));
    assert_eq!(field_of(&with("ga.population", Value::Int(1))), Some("ga.population"));
    let small = with("ga.population", Value::Int(10));
    assert_eq!(field_of(&small), Some("acquire.seed_immigrants"));
    let mut t = small;
    t.acquire.seed_immigrants = 0;
    t.acquire.idle_individuals = 0;
    assert_eq!(t.validate(64), Ok(()));
    t.ga.immigrants = 9;
    assert_eq!(field_of(&t), Some("ga.immigrants"));
}

#[test]
fn wrong_kinds_and_ranges_are_refused_by_the_setters() {
    let mut t = Tuning::DEFAULT;
    let e = t.set("ga.mutation_prob", Value::Int(1)).unwrap_err();
    assert_eq!(e.field, "ga.mutation_prob");
    let e = t.set("status.lose_frames", Value::Int(70_000)).unwrap_err();
    assert_eq!(format!("{e}"), "tracker.status.lose_frames: is too large for its integer type");
    let e = t.set("method", Value::Name("fast")).unwrap_err();
    assert_eq!(e.field, "method");
    assert_eq!(t.set("no.such", Value::Int(1)).unwrap_err().rule, "is not a tuning field");
    assert_eq!(t, Tuning::DEFAULT);
}

#[test]
fn the_method_names_the_feedforward_mode() {
    for (name, mode) in Feedforward::NAMES.iter().zip([Feedforward::Off, Feedforward::On, Feedforward::OnWithTarget]) {
        let t = with("method", Value::Name(name));
        assert_eq!(t.feedforward, mode);
        assert_eq!(t.get("method"), Some(Value::Name(name)));
    }
}

#[test]
fn a_feedforward_mode_reads_back_from_its_name() {
    for (mode, name) in Feedforward::ALL.into_iter().zip(Feedforward::NAMES) {
        assert_eq!(format!("{mode}"), name);
        assert_eq!(name.parse::<Feedforward>(), Ok(mode));
    }
    assert_eq!(Feedforward::OnWithTarget.name(), "ff+target");
    let e = "FF".parse::<Feedforward>().unwrap_err();
    assert_eq!((e.text(), format!("{e}").as_str()), ("FF", "expected \"ga\", \"ff\" or \"ff+target\", got \"FF\""));
    let long = "é".repeat(20);
    let e = long.parse::<Feedforward>().unwrap_err();
    assert_eq!(e.text(), "é".repeat(16));
    assert!(format!("{e}").ends_with("ééé…\""));
}

#[test]
fn the_target_rows_check_the_target_model_alone() {
    let mut p = TargetFilterParams::DEFAULT;
    assert_eq!(p.validate(), Ok(()));
    p.max_gap_s = f32::INFINITY;
    assert_eq!(p.validate().unwrap_err().field, "target.max_gap_s");
}
