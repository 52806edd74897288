//! `/joint_states` as the joint table of a sequence: joints found by *name* (any order; joints
//! not on the URDF chain, e.g. a gripper's, ignored; a missing chain joint is an error naming
//! it), samples ordered by `header.stamp`.
//!
//! ## Velocities
//! When every message carries a velocity per joint, those are used. When any message has an
//! empty `velocity` (the usual case), every sample's velocity is derived from the positions by
//! the **central difference** `q̇_i = (q_{i+1} − q_{i−1}) / (t_{i+1} − t_{i−1})` (one-sided at
//! the first and last sample); the frame's `q̇` is then interpolated linearly at its capture
//! time like `q` (see [`crate::recording::sequence::tables`]). The error is `O(h²)` in the sample spacing
//! `h` (e.g. 1e-5 rad/s for a 0.5 rad/s sway sampled at 500 Hz; tested against the true
//! velocity of a known trajectory).

use crate::recording::sequence::JointTable;

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

/// The joint messages of a bag as read, compactly (a long recording holds hundreds of
/// thousands): each distinct list of names stored once, the values in one flat array.
#[derive(Debug, Clone, Default)]
pub struct JointMessages {
    name_lists: Vec<Vec<String>>,
    messages: Vec<Stored>,
    /// Per message: its positions, then its velocities when it has them.
    values: Vec<f64>,
}

/// One message: its index on the topic, stamp, name list, first value, and whether it has
/// velocities.
#[derive(Debug, Clone, Copy)]
struct Stored {
    index: usize,
    stamp_ns: i64,
    names: usize,
    start: usize,
    has_velocity: bool,
}

impl JointMessages {
    /// Adds message `index` of the topic.
    ///
    /// # Errors
    /// Names, positions and velocities whose numbers disagree.
    pub fn push(&mut self, index: usize, m: JointState) -> Result<(), String> {
        if m.position.len() != m.name.len() {
            return Err(format!("{} names but {} positions", m.name.len(), m.position.len()));
        }
        let has_velocity = !m.velocity.is_empty();
        if has_velocity && m.velocity.len() != m.name.len() {
            return Err(format!("{} names but {} velocities", m.name.len(), m.velocity.len()));
        }
        let names = match self.name_lists.iter().rposition(|l| *l == m.name) {
            Some(k) => k,
            None => {
                self.name_lists.push(m.name);
                self.name_lists.len() - 1
            }
        };
        let start = self.values.len();
        self.values.extend(m.position.iter().chain(&m.velocity));
        self.messages.push(Stored { index, stamp_ns: m.header.stamp_ns, names, start, has_velocity });
        Ok(())
    }

    /// Number of messages.
    pub fn len(&self) -> usize {
        self.messages.len()
    }

    /// Whether there is none.
    pub fn is_empty(&self) -> bool {
        self.messages.is_empty()
    }

    /// Message `m`'s chain values (positions, then velocities or zeros) appended to `out`;
    /// `cols` maps the chain's joints to the message's names.
    fn chain_values(&self, m: &Stored, cols: &[usize], chain: &[String], out: &mut Vec<f64>) -> Result<(), String> {
        let n = self.name_lists[m.names].len();
        let value = |k: usize| self.values[m.start + k];
        let velocity = |c: usize| if m.has_velocity { value(n + c) } else { 0.0 };
        for (&c, name) in cols.iter().zip(chain) {
            let (p, v) = (value(c), velocity(c));
            if !p.is_finite() || !v.is_finite() {
                return Err(format!("joint '{name}': position {p} / velocity {v} is not finite"));
            }
            out.push(p);
        }
        out.extend(cols.iter().map(|&c| velocity(c)));
        Ok(())
    }
}

/// Where each joint of `chain` is in the message names `list`.
fn columns(list: &[String], chain: &[String]) -> Result<Vec<usize>, String> {
    chain
        .iter()
        .map(|n| {
            list.iter().position(|x| x == n).ok_or_else(|| {
                format!("joint '{n}' of the URDF chain is missing (the message names {})", list.join(", "))
            })
        })
        .collect()
}

/// The joint table of `messages` over the chain `names`; times are `(stamp − origin_ns) / 1e9`
/// s. Returns the table, how velocities were obtained and the number of messages dropped for
/// repeating an earlier stamp.
///
/// # Errors
/// `(message index, what)`: a missing chain joint, a non-finite value, fewer than two samples.
pub fn table(
    messages: &JointMessages,
    names: &[String],
    origin_ns: i64,
) -> Result<(JointTable, Velocities, usize), (Option<usize>, String)> {
    let lists: Vec<Result<Vec<usize>, String>> = messages.name_lists.iter().map(|l| columns(l, names)).collect();
    let mut order: Vec<&Stored> = messages.messages.iter().collect();
    // Every message is checked, in message order, before duplicates are dropped.
    for m in &order {
        lists[m.names].as_ref().map_err(|e| (Some(m.index), e.clone()))?;
    }
    order.sort_by_key(|m| (m.stamp_ns, m.index));
    let before = order.len();
    order.dedup_by_key(|m| m.stamp_ns);
    let dropped = before - order.len();
    if order.len() < 2 {
        return Err((None, format!("{} joint sample(s) with distinct stamps: at least 2 are needed", order.len())));
    }
    // Per sample: q then q̇ (as recorded, or zeros until derived below).
    let mut values = Vec::with_capacity(order.len() * 2 * names.len());
    for m in &order {
        let cols = lists[m.names].as_ref().map_err(|e| (Some(m.index), e.clone()))?;
        messages.chain_values(m, cols, names, &mut values).map_err(|e| (Some(m.index), e))?;
    }
    let times: Vec<f64> = order.iter().map(|m| (m.stamp_ns - origin_ns) as f64 / 1e9).collect();
    let recorded = order.iter().all(|m| m.has_velocity);
    if !recorded {
        central_differences(&times, &mut values, names.len());
    }
    let how = if recorded { Velocities::Recorded } else { Velocities::Derived };
    Ok((JointTable::from_flat(names.to_vec(), times, values), how, dropped))
}

/// Replaces the velocities of `rows` (per sample `dof` positions, then `dof` velocities) by
/// the central differences of the positions over `t` (one-sided at the ends); at least two
/// samples.
pub fn central_differences(t: &[f64], rows: &mut [f64], dof: usize) {
    let n = t.len();
    let mut qd = Vec::with_capacity(n * dof);
    for i in 0..n {
        let (a, b) = (i.saturating_sub(1), (i + 1).min(n - 1));
        let dt = t[b] - t[a];
        qd.extend((0..dof).map(|j| (rows[2 * dof * b + j] - rows[2 * dof * a + j]) / dt));
    }
    for (i, v) in qd.chunks(dof).enumerate() {
        rows[2 * dof * i + dof..2 * dof * (i + 1)].copy_from_slice(v);
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;
    use crate::rig::bag::msgs::Header;

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
        let mut messages = JointMessages::default();
        for k in 0..1000 {
            let t = k as f64 * 0.002;
            let m = msg(k as i64 * 2_000_000, &["grip", "j2", "j1"], vec![0.0, 0.1 * t * t, a * (w * t).sin()]);
            messages.push(k, m).unwrap();
        }
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
        let of = |ms: &[(usize, &JointState)]| {
            let mut out = JointMessages::default();
            ms.iter().for_each(|(i, m)| out.push(*i, (*m).clone()).unwrap());
            out
        };
        let (t, how, _) = table(&of(&[(0, &m1), (1, &m0)]), &names, 0).unwrap();
        assert_eq!(how, Velocities::Recorded);
        assert_eq!(t.at(0.0).unwrap().qd, vec![0.5]);
        let err = table(&of(&[(0, &m0), (4, &msg(10, &["b"], vec![2.0]))]), &names, 0).unwrap_err();
        assert_eq!(err.0, Some(4));
        assert!(err.1.contains("joint 'a'") && err.1.contains("missing"), "{}", err.1);
    }
}
