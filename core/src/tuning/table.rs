//! The table of [`Tuning`]'s fields, in the order every serialization uses.

use super::{Feedforward, Field, Kind, Rule, Tuning, Value, count, int, method_name, real, set_method};

/// Every tuning field, in order: the run's mode and limits, the GA, the acquisition, the
/// status thresholds, the target motion model.
pub const FIELDS: [Field; 56] = [
    Field {
        name: "method",
        unit: "",
        meaning: "what is fed forward: ga (nothing), ff (the arm's motion), ff+target (also the block's own)",
        kind: Kind::Name(&Feedforward::NAMES),
        rule: Rule::Any,
        get: |t: &Tuning| method_name(t.feedforward),
        set: set_method,
    },
    int!(
        "hue_tolerance",
        "hue unit (2°)",
        Any,
        "narrowest half-width of a face's hue band; the search band is 13 units wider (below 90)",
        hue_tolerance
    ),
    real!("max_dt_s", "s", Positive, "longest time step between frames accepted", max_dt_s),
    int!(
        "generations_per_frame",
        "generations",
        Any,
        "GA generations on each frame pair (1 to 4; 1 is the paper's 1-step GA)",
        generations_per_frame
    ),
    int!(
        "ga.population",
        "individuals",
        Any,
        "individuals evaluated and bred per generation (2 to the compiled capacity)",
        ga.population
    ),
    real!("ga.crossover_prob", "probability", Unit, "chance a child blends its two parents", ga.crossover_prob),
    real!("ga.mutation_prob", "probability", Unit, "chance a child is mutated", ga.mutation_prob),
    real!(
        "ga.gene_mutation_prob",
        "probability",
        Unit,
        "chance each gene of a mutated child moves",
        ga.gene_mutation_prob
    ),
    int!("ga.immigrants", "individuals", Any, "fresh uniform samples per generation", ga.immigrants),
    int!("ga.tournament", "individuals", AtLeastOne, "individuals per tournament", ga.tournament),
    real!("ga.level_cdf.coarse", "probability", Unit, "chance of the coarse mutation scale", ga.level_cdf[0]),
    real!("ga.level_cdf.medium", "probability", Unit, "chance of the coarse or the medium scale", ga.level_cdf[1]),
    real!(
        "ga.settled_level_cdf.coarse",
        "probability",
        Unit,
        "ga.level_cdf.coarse once settled",
        ga.settled_level_cdf[0]
    ),
    real!(
        "ga.settled_level_cdf.medium",
        "probability",
        Unit,
        "ga.level_cdf.medium once settled",
        ga.settled_level_cdf[1]
    ),
    real!(
        "ga.settled_fitness",
        "fitness",
        Finite,
        "elite fitness from which the settled CDF is used (above 1: never)",
        ga.settled_fitness
    ),
    real!(
        "ga.mutation_scale.coarse.x",
        "m",
        NonNegative,
        "coarse mutation half-width, lateral x",
        ga.mutation_scale[0][0]
    ),
    real!(
        "ga.mutation_scale.coarse.y",
        "m",
        NonNegative,
        "coarse mutation half-width, lateral y",
        ga.mutation_scale[0][1]
    ),
    real!(
        "ga.mutation_scale.coarse.depth",
        "m",
        NonNegative,
        "coarse mutation half-width, depth along the viewing ray",
        ga.mutation_scale[0][2]
    ),
    real!(
        "ga.mutation_scale.coarse.turn_x",
        "ε (½ rad)",
        NonNegative,
        "coarse mutation half-width, turn about the camera's x",
        ga.mutation_scale[0][3]
    ),
    real!(
        "ga.mutation_scale.coarse.turn_y",
        "ε (½ rad)",
        NonNegative,
        "coarse mutation half-width, turn about the camera's y",
        ga.mutation_scale[0][4]
    ),
    real!(
        "ga.mutation_scale.coarse.turn_z",
        "ε (½ rad)",
        NonNegative,
        "coarse mutation half-width, turn about the camera's z",
        ga.mutation_scale[0][5]
    ),
    real!(
        "ga.mutation_scale.medium.x",
        "m",
        NonNegative,
        "medium mutation half-width, lateral x",
        ga.mutation_scale[1][0]
    ),
    real!(
        "ga.mutation_scale.medium.y",
        "m",
        NonNegative,
        "medium mutation half-width, lateral y",
        ga.mutation_scale[1][1]
    ),
    real!(
        "ga.mutation_scale.medium.depth",
        "m",
        NonNegative,
        "medium mutation half-width, depth along the viewing ray",
        ga.mutation_scale[1][2]
    ),
    real!(
        "ga.mutation_scale.medium.turn_x",
        "ε (½ rad)",
        NonNegative,
        "medium mutation half-width, turn about the camera's x",
        ga.mutation_scale[1][3]
    ),
    real!(
        "ga.mutation_scale.medium.turn_y",
        "ε (½ rad)",
        NonNegative,
        "medium mutation half-width, turn about the camera's y",
        ga.mutation_scale[1][4]
    ),
    real!(
        "ga.mutation_scale.medium.turn_z",
        "ε (½ rad)",
        NonNegative,
        "medium mutation half-width, turn about the camera's z",
        ga.mutation_scale[1][5]
    ),
    real!("ga.mutation_scale.fine.x", "m", NonNegative, "fine mutation half-width, lateral x", ga.mutation_scale[2][0]),
    real!("ga.mutation_scale.fine.y", "m", NonNegative, "fine mutation half-width, lateral y", ga.mutation_scale[2][1]),
    real!(
        "ga.mutation_scale.fine.depth",
        "m",
        NonNegative,
        "fine mutation half-width, depth along the viewing ray",
        ga.mutation_scale[2][2]
    ),
    real!(
        "ga.mutation_scale.fine.turn_x",
        "ε (½ rad)",
        NonNegative,
        "fine mutation half-width, turn about the camera's x",
        ga.mutation_scale[2][3]
    ),
    real!(
        "ga.mutation_scale.fine.turn_y",
        "ε (½ rad)",
        NonNegative,
        "fine mutation half-width, turn about the camera's y",
        ga.mutation_scale[2][4]
    ),
    real!(
        "ga.mutation_scale.fine.turn_z",
        "ε (½ rad)",
        NonNegative,
        "fine mutation half-width, turn about the camera's z",
        ga.mutation_scale[2][5]
    ),
    int!(
        "acquire.scan_stride",
        "px",
        AtLeastOne,
        "every n-th pixel of every n-th row is scanned for the faces' hues",
        acquire.scan_stride
    ),
    int!("acquire.scan_chunk", "grid pixels", AtLeastOne, "scan work per image per generation", acquire.scan_chunk),
    int!(
        "acquire.seed_immigrants",
        "individuals",
        Any,
        "children replaced by poses seeded from the blobs while not tracking",
        acquire.seed_immigrants
    ),
    int!(
        "acquire.idle_individuals",
        "individuals",
        Any,
        "individuals left unevaluated in a generation that starts acquiring",
        acquire.idle_individuals
    ),
    int!(
        "acquire.min_face_hits",
        "grid hits",
        Any,
        "hits of a face's hue needed in each image for the face to count",
        acquire.min_face_hits
    ),
    real!(
        "acquire.spread_m.fine",
        "m",
        NonNegative,
        "position half-width of the finest seeded perturbation",
        acquire.spread_m[0]
    ),
    real!(
        "acquire.spread_m.medium",
        "m",
        NonNegative,
        "position half-width of the medium seeded perturbation",
        acquire.spread_m[1]
    ),
    real!(
        "acquire.spread_m.coarse",
        "m",
        NonNegative,
        "position half-width of the coarsest seeded perturbation",
        acquire.spread_m[2]
    ),
    real!(
        "acquire.spread_rad.fine",
        "rad",
        NonNegative,
        "rotation half-width of the finest seeded perturbation",
        acquire.spread_rad[0]
    ),
    real!(
        "acquire.spread_rad.medium",
        "rad",
        NonNegative,
        "rotation half-width of the medium seeded perturbation",
        acquire.spread_rad[1]
    ),
    real!(
        "acquire.spread_rad.coarse",
        "rad",
        NonNegative,
        "rotation half-width of the coarsest seeded perturbation",
        acquire.spread_rad[2]
    ),
    real!(
        "status.acquire_fitness",
        "fitness",
        Unit,
        "fitness relative to the expected score in the current light at or above which a pose counts as found",
        status.acquire_fitness
    ),
    int!(
        "status.confirm_frames",
        "frames",
        AtLeastOne,
        "frames in a row found before held, and certain before tracking (one status decision per frame)",
        status.confirm_frames
    ),
    real!(
        "status.certain_fitness",
        "fitness",
        Unit,
        "lower camera's fitness relative to the expected score at or above which a held pose is reported tracking",
        status.certain_fitness
    ),
    real!(
        "status.lose_fitness",
        "fitness",
        Unit,
        "fitness relative to the expected score in the current light below which a tracked block counts as gone",
        status.lose_fitness
    ),
    int!("status.lose_frames", "frames", AtLeastOne, "frames in a row gone before lost", status.lose_frames),
    int!(
        "status.lost_frames_to_search",
        "frames",
        AtLeastOne,
        "frames lost before searching again",
        status.lost_frames_to_search
    ),
    real!(
        "target.acceleration_m_s2",
        "m/s²",
        Positive,
        "largest linear acceleration of the block expected",
        target.acceleration_m_s2
    ),
    real!(
        "target.angular_acceleration_rad_s2",
        "rad/s²",
        Positive,
        "largest angular acceleration of the block expected",
        target.angular_acceleration_rad_s2
    ),
    real!("target.max_speed_m_s", "m/s", Positive, "largest speed of the block when first seen", target.max_speed_m_s),
    real!(
        "target.max_rate_rad_s",
        "rad/s",
        Positive,
        "largest angular speed of the block when first seen",
        target.max_rate_rad_s
    ),
    real!("target.image_noise_px", "px", Positive, "one estimate's image noise per camera", target.image_noise_px),
    real!("target.max_gap_s", "s", Positive, "a longer gap between estimates restarts the model", target.max_gap_s),
];
