//! `/joint_states` as the joint table of a sequence: joints found by *name* (any order; joints
//! not on the URDF chain, e.g. a gripper's, ignored; a missing chain joint is an error naming
//! it), samples ordered by `header.stamp`.
//!
//! ## Velocities
//! When every message carries a velocity per joint, those are used. When any message has an
//! empty `velocity` (the usual case), every sample's velocity is derived from the positions by
//! the **central difference** `q̇_i = (q_{i+1} − q_{i−1}) / (t_{i+1} − t_{i−1})` (one-sided at
//! the first and last sample); the frame's `q̇` is then interpolated linearly at its capture
//! time like `q` (see [`crate::sequence::tables`]). The error is `O(h²)` in the sample spacing
//! `h` (e.g. 1e-5 rad/s for a 0.5 rad/s sway sampled at 500 Hz; tested against the true
//! velocity of a known trajectory).

use crate::sequence::JointTable;

use super::msgs::JointState;

/// How the velocities were obtained.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Velocities {
    /// As recorded in the messages.
    Recorded,
    /// Central differences of the positions.
    Derived,
}

/// One message's chain values: stamp, message index, q, q̇ when recorded.
type Sample = (i64, usize, Vec<f64>, Option<Vec<f64>>);

/// The joint table of `messages` ((message index, message), any order) over the chain `names`;
/// times are `(stamp − origin_ns) / 1e9` s. Returns the table, how velocities were obtained
/// and the number of messages dropped for repeating an earlier stamp.
///
/// # Errors
/// `(message index, what)`: a missing chain joint, lengths that disagree, a non-finite value,
/// fewer than two samples.
pub fn table(
    messages: &[(usize, JointState)],
    names: &[String],
    origin_ns: i64,
) -> Result<(JointTable, Velocities, usize), (Option<usize>, String)> {
    let mut samples: Vec<Sample> = Vec::with_capacity(messages.len());
    for (index, m) in messages {
        let (q, qd) = chain_values(m, names).map_err(|e| (Some(*index), e))?;
        samples.push((m.header.stamp_ns, *index, q, qd));
    }
    samples.sort_by_key(|s| (s.0, s.1));
    let before = samples.len();
    samples.dedup_by_key(|s| s.0);
    let dropped = before - samples.len();
    if samples.len() < 2 {
        return Err((None, format!("{} joint sample(s) with distinct stamps: at least 2 are needed", samples.len())));
    }
    let times: Vec<f64> = samples.iter().map(|s| (s.0 - origin_ns) as f64 / 1e9).collect();
    let recorded = samples.iter().all(|s| s.3.is_some());
    let rows: Vec<(f64, Vec<f64>, Vec<f64>)> = if recorded {
        samples.into_iter().zip(&times).map(|(s, t)| (*t, s.2, s.3.unwrap_or_default())).collect()
    } else {
        let q: Vec<Vec<f64>> = samples.into_iter().map(|s| s.2).collect();
        let qd = central_differences(&times, &q);
        times.iter().zip(q).zip(qd).map(|((t, q), qd)| (*t, q, qd)).collect()
    };
    let how = if recorded { Velocities::Recorded } else { Velocities::Derived };
    Ok((JointTable::from_samples(names.to_vec(), &rows), how, dropped))
}

/// The chain's positions (and velocities, when the message has them) of one message.
fn chain_values(m: &JointState, names: &[String]) -> Result<(Vec<f64>, Option<Vec<f64>>), String> {
    if m.position.len() != m.name.len() {
        return Err(format!("{} names but {} positions", m.name.len(), m.position.len()));
    }
    let has_velocity = !m.velocity.is_empty();
    if has_velocity && m.velocity.len() != m.name.len() {
        return Err(format!("{} names but {} velocities", m.name.len(), m.velocity.len()));
    }
    let mut q = Vec::with_capacity(names.len());
    let mut qd = Vec::with_capacity(names.len());
    for n in names {
        let Some(k) = m.name.iter().position(|x| x == n) else {
            return Err(format!("joint '{n}' of the URDF chain is missing (the message names {})", m.name.join(", ")));
        };
        let (p, v) = (m.position[k], m.velocity.get(k).copied().unwrap_or(0.0));
        if !p.is_finite() || !v.is_finite() {
            return Err(format!("joint '{n}': position {p} / velocity {v} is not finite"));
        }
        q.push(p);
        qd.push(v);
    }
    Ok((q, has_velocity.then_some(qd)))
}

/// Central differences of `q` over `t` (one-sided at the ends); at least two samples.
pub fn central_differences(t: &[f64], q: &[Vec<f64>]) -> Vec<Vec<f64>> {
    let n = t.len();
    (0..n)
        .map(|i| {
            let (a, b) = (i.saturating_sub(1), (i + 1).min(n - 1));
            let dt = t[b] - t[a];
            q[b].iter().zip(&q[a]).map(|(qb, qa)| (qb - qa) / dt).collect()
        })
        .collect()
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;
    use crate::bag::msgs::Header;

    fn msg(t_ns: i64, names: &[&str], pos: Vec<f64>) -> JointState {
        JointState {
            header: Header { stamp_ns: t_ns, frame_id: String::new() },
            name: names.iter().map(|s| (*s).to_owned()).collect(),
            position: pos,
            velocity: vec![],
        }
    }

    #[test]
    fn derived_velocity_matches_the_true_velocity_at_frame_times() {
        // q1 = 0.3 sin(2t), q2 = 0.1 t², sampled at 500 Hz with names shuffled and a gripper.
        let (a, w) = (0.3, 2.0);
        let names = vec!["j1".to_owned(), "j2".to_owned()];
        let messages: Vec<(usize, JointState)> = (0..1000)
            .map(|k| {
                let t = k as f64 * 0.002;
                (k, msg(k as i64 * 2_000_000, &["grip", "j2", "j1"], vec![0.0, 0.1 * t * t, a * (w * t).sin()]))
            })
            .collect();
        let (table, how, dropped) = table(&messages, &names, 0).unwrap();
        assert_eq!((how, dropped), (Velocities::Derived, 0));
        // Frames at 30 Hz, between the samples.
        for f in 1..59 {
            let t = f as f64 / 30.0 + 0.0007;
            let s = table.at(t).unwrap();
            assert!((s.q[0] - a * (w * t).sin()).abs() < 1e-5, "q at {t}");
            assert!(
                (s.qd[0] - a * w * (w * t).cos()).abs() < 2e-5,
                "q̇1 at {t}: {} vs {}",
                s.qd[0],
                a * w * (w * t).cos()
            );
            assert!((s.qd[1] - 0.2 * t).abs() < 1e-9, "q̇2 at {t}");
        }
    }

    #[test]
    fn recorded_velocities_are_used_and_bad_messages_named() {
        let mut m0 = msg(0, &["a"], vec![1.0]);
        m0.velocity = vec![0.5];
        let mut m1 = msg(10, &["a"], vec![2.0]);
        m1.velocity = vec![0.7];
        let names = vec!["a".to_owned()];
        let (t, how, _) = table(&[(0, m1.clone()), (1, m0.clone())], &names, 0).unwrap();
        assert_eq!(how, Velocities::Recorded);
        assert_eq!(t.at(0.0).unwrap().qd, vec![0.5]);
        let err = table(&[(0, m0), (4, msg(10, &["b"], vec![2.0]))], &names, 0).unwrap_err();
        assert_eq!(err.0, Some(4));
        assert!(err.1.contains("joint 'a'") && err.1.contains("missing"), "{}", err.1);
    }
}
