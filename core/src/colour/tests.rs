use super::*;
use crate::limits::DEFAULT_HUE_TOLERANCE;

const PRIOR: [u8; FACES] = [0, 60, 120, 0, 60, 120];

/// A tally of `n` points of face `k` at each of `hues`.
fn tally_of(_model: &ColourModel, k: usize, hues: &[u8], n: usize) -> Tally {
    let mut tally = Tally::EMPTY;
    for _ in 0..n {
        tally.add(k, hues);
    }
    tally
}

#[test]
fn a_face_not_learnt_yet_keeps_its_search_band() {
    let mut model = ColourModel::new(PRIOR, DEFAULT_HUE_TOLERANCE);
    let wide = DEFAULT_HUE_TOLERANCE + MAX_HUE_SHIFT;
    assert_eq!(model.bands(), model.search_bands());
    assert!(model.search_bands().iter().all(|b| b.half == wide));
    // Red seen at its configured hue: its band narrows to the tolerance, the others stay wide.
    model.learn(&tally_of(&model, 0, &[0], 20));
    for (k, band) in model.bands().iter().enumerate() {
        let half = if k == 0 { DEFAULT_HUE_TOLERANCE } else { wide };
        assert_eq!(*band, Band { centre: PRIOR[k], half }, "face {k}");
    }
    let model = ColourModel::new(PRIOR, DEFAULT_HUE_TOLERANCE);
    assert_eq!(model.expected_fitness(), 1.0);
    assert_eq!(model.hue_deg(2), 240.0);
}

#[test]
fn the_first_sighting_sets_the_hue_and_later_ones_refine_it() {
    let mut model = ColourModel::new(PRIOR, DEFAULT_HUE_TOLERANCE);
    // Blue seen at 224° (112 units), eight units below the prior, with a spread of one unit.
    assert!(model.learn(&tally_of(&model, 2, &[111, 112, 113], 10)));
    assert_eq!(model.bands()[2].centre, 112);
    assert_eq!(model.bands()[2].half, DEFAULT_HUE_TOLERANCE, "a narrow spread keeps the configured width");
    assert_eq!(model.frames_seen(2), 1);
    assert_eq!(model.frames_seen(5), 0, "the opposite face is learnt separately");
    assert!((model.hue_deg(2) - 224.0).abs() < 0.01);
    // A wide spread (±12 units, standard deviation 12) widens the band, within the search band.
    for _ in 0..20 {
        model.learn(&tally_of(&model, 2, &[100, 124], 10));
    }
    let band = model.bands()[2];
    assert_eq!(band.centre, 112);
    assert_eq!(band.half, model.search_half_width(), "{band:?}");
}

#[test]
fn hues_outside_the_search_band_and_without_hue_are_not_learnt() {
    let mut model = ColourModel::new(PRIOR, DEFAULT_HUE_TOLERANCE);
    // Green (60 units) seen as yellow-green 45 and as red 0 (another face's colour) and NO_HUE.
    let tally = tally_of(&model, 1, &[48, 0, crate::limits::NO_HUE], 20);
    assert_eq!(tally.points(1), 60);
    assert_eq!(tally.within(1, 60, model.search_half_width()).count, 20);
    assert_eq!(tally.within(1, 60, DEFAULT_HUE_TOLERANCE).count, 0);
    model.learn(&tally);
    assert_eq!(model.bands()[1].centre, 48);
    // Too few points: nothing learnt.
    let before = model;
    assert!(!model.learn(&tally_of(&model, 1, &[50], COLOUR_MIN_SAMPLES as usize - 1)));
    assert_eq!(model, before);
}

#[test]
fn the_learnt_hue_stays_within_the_largest_shift() {
    let mut model = ColourModel::new(PRIOR, DEFAULT_HUE_TOLERANCE);
    // Red pulled ever further towards magenta: each frame sees it at the edge of its window.
    for _ in 0..100 {
        let band = model.bands()[0];
        let edge = (i32::from(band.centre) - i32::from(model.search_half_width())).rem_euclid(180) as u8;
        model.learn(&tally_of(&model, 0, &[edge], 20));
    }
    assert_eq!(model.bands()[0].centre, 180 - MAX_HUE_SHIFT);
    assert!((model.hue_deg(0) - (360.0 - 2.0 * f32::from(MAX_HUE_SHIFT))).abs() < 0.01);
}

#[test]
fn the_expected_fitness_is_the_share_of_points_in_band() {
    let mut model = ColourModel::new(PRIOR, DEFAULT_HUE_TOLERANCE);
    // Three of four points of red in band, the fourth a highlight without hue.
    for _ in 0..50 {
        model.learn(&tally_of(&model, 0, &[0, 1, 179, crate::limits::NO_HUE], 10));
    }
    assert!((model.expected_fitness() - 0.75).abs() < 0.01, "{}", model.expected_fitness());
    // Never below the floor.
    for _ in 0..50 {
        model.learn(&tally_of(
            &model,
            0,
            &[0, crate::limits::NO_HUE, crate::limits::NO_HUE, crate::limits::NO_HUE],
            20,
        ));
    }
    assert_eq!(model.expected_fitness(), MIN_EXPECTED_FITNESS);
    model.reset();
    assert_eq!(model, ColourModel::new(PRIOR, DEFAULT_HUE_TOLERANCE));
}

#[test]
fn the_table_follows_the_status_and_the_model() {
    let mut colours = Colours::new(PRIOR, DEFAULT_HUE_TOLERANCE);
    let search = HueLut::new(&PRIOR, DEFAULT_HUE_TOLERANCE + MAX_HUE_SHIFT);
    assert_eq!((*colours.lut(), colours.is_tracking()), (search, false));
    colours.select(true);
    assert_eq!(*colours.lut(), search, "nothing learnt yet: every face has its search band");
    let tally = tally_of(colours.model(), 2, &[112], 20);
    colours.learn(&tally);
    // The learnt face at its own band; the opposite face (same prior) keeps its search band.
    assert_eq!(colours.lut().mask(112 - DEFAULT_HUE_TOLERANCE), 1 << 2 | 1 << 5);
    assert_eq!(colours.lut().mask(112 + DEFAULT_HUE_TOLERANCE + 1) & 1 << 2, 0);
    assert_ne!(colours.lut().mask(120 + DEFAULT_HUE_TOLERANCE + 1) & 1 << 5, 0, "the opposite face is not learnt");
    colours.select(false);
    assert_eq!(*colours.lut(), search, "the search table ignores what was learnt");
    // Learning while searching changes the model, not the table.
    colours.learn(&tally_of(colours.model(), 1, &[50], 20));
    assert_eq!(*colours.lut(), search);
    colours.select(true);
    assert_eq!(colours.lut().mask(50), 1 << 1 | 1 << 4);
    assert_eq!(colours.lut().mask(50 + DEFAULT_HUE_TOLERANCE + 1), 1 << 4, "learnt green is narrow, face 4 is not");
}

#[test]
fn a_census_point_that_shows_another_colour_does_not_lower_the_expected_fitness() {
    let window = DEFAULT_HUE_TOLERANCE + MAX_HUE_SHIFT;
    let learnt = |odd: u8| {
        let mut model = ColourModel::new(PRIOR, DEFAULT_HUE_TOLERANCE);
        for _ in 0..50 {
            model.learn(&tally_of(&model, 0, &[0, 1, 179, odd], 10));
        }
        model.expected_fitness()
    };
    // Green, the next face's colour, on the red face's census (the pose is off the face): not a
    // light loss; nor blue from the far side of the hue circle.
    assert_eq!(learnt(60), 1.0);
    assert_eq!(learnt(120 + window), 1.0);
    // No hue at all (a highlight, a shadow), or a colour no face has (a reflection): what the
    // true pose loses under this light.
    for odd in [crate::limits::NO_HUE, window + 1] {
        let f = learnt(odd);
        assert!((f - 0.75).abs() < 0.01, "hue {odd}: {f}");
    }
}

#[test]
fn the_confirming_scale_rises_like_the_expected_fitness_and_falls_four_times_slower() {
    let mut model = ColourModel::new(PRIOR, DEFAULT_HUE_TOLERANCE);
    let all = [0u8, 1, 179, 0];
    let three_of_four = [0u8, 1, 179, crate::limits::NO_HUE];
    // The first sighting sets both scales.
    model.learn(&tally_of(&model, 0, &three_of_four, 10));
    assert_eq!(model.confirming_fitness(), model.expected_fitness());
    assert!((model.confirming_fitness() - 0.75).abs() < 0.01);
    // A frame above them moves both alike.
    model.learn(&tally_of(&model, 0, &all, 10));
    assert_eq!(model.confirming_fitness(), model.expected_fitness());
    // Frames of full coverage, then frames of poses that cover less: the expected fitness follows
    // them down, the confirming scale four times more slowly.
    for _ in 0..60 {
        model.learn(&tally_of(&model, 0, &all, 10));
    }
    for _ in 0..10 {
        model.learn(&tally_of(&model, 0, &three_of_four, 10));
    }
    let (expected, confirming) = (model.expected_fitness(), model.confirming_fitness());
    assert!((1.0 - confirming) * 3.0 < 1.0 - expected, "expected {expected}, confirming {confirming}");
    // A light that stays darker is followed all the same.
    for _ in 0..600 {
        model.learn(&tally_of(&model, 0, &three_of_four, 10));
    }
    assert!((model.confirming_fitness() - 0.75).abs() < 0.01, "{}", model.confirming_fitness());
}

#[test]
fn the_scenes_hues_leave_the_search_bands_and_not_the_learnt_ones() {
    let mut colours = Colours::new(PRIOR, DEFAULT_HUE_TOLERANCE);
    // A tinted background at 86°–96° (43–48 units), inside green's search band (42–78 units).
    let mut scene = HueSet::EMPTY;
    (43..=48).for_each(|h| scene.insert(h));
    assert_eq!(colours.lut().mask(45), 1 << 1 | 1 << 4);
    colours.set_scene(&scene);
    assert_eq!(colours.scene_in_search_bands(), [0, 6, 0, 0, 6, 0]);
    assert_eq!(colours.lut().mask(45), 0);
    assert_eq!(colours.lut().mask(42), 1 << 1 | 1 << 4, "the band's other hues still match");
    assert_eq!(colours.lut().any(1 << 1)[45], 0, "and so do the face planes");
    // Green learnt at 92° (46 units): its learnt band keeps the hue; face 4, not learnt, does not.
    colours.select(true);
    colours.learn(&tally_of(colours.model(), 1, &[46], 20));
    assert_eq!(colours.lut().mask(46), 1 << 1);
    // A new configuration forgets the scene.
    colours.configure(PRIOR, DEFAULT_HUE_TOLERANCE);
    assert_eq!(colours.lut().mask(45), 1 << 1 | 1 << 4);
}
