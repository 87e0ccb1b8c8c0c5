//! The Pareto front of time against error: the configurations no other one beats in both.

/// One point: its time (any unit, smaller is better), its error (smaller is better), and
/// whether it is usable at all (a configuration with NaN/Inf never is, whatever its error).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Point {
    /// Cost, e.g. median render time in seconds.
    pub time: f64,
    /// Error, e.g. mean relative error.
    pub error: f64,
    /// Whether the point may be on the front.
    pub usable: bool,
}

/// For each point, whether it is on the front: usable, and no other usable point is at least
/// as fast and at least as accurate and strictly better in one of the two. O(n²), which is
/// fine for the few hundred configurations a sweep has.
pub fn front(points: &[Point]) -> Vec<bool> {
    points
        .iter()
        .enumerate()
        .map(|(i, p)| {
            p.usable
                && !points.iter().enumerate().any(|(j, q)| {
                    j != i
                        && q.usable
                        && q.time <= p.time
                        && q.error <= p.error
                        && (q.time < p.time || q.error < p.error)
                })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dominated_and_unusable_points_are_off_the_front() {
        let p = |time, error, usable| Point { time, error, usable };
        let points =
            [p(10.0, 0.5, true), p(20.0, 0.1, true), p(20.0, 0.3, true), p(30.0, 0.1, true), p(5.0, 0.9, true)];
        assert_eq!(front(&points), [true, true, false, false, true]);
        assert_eq!(front(&[p(1.0, 0.0, false), p(2.0, 1.0, true)]), [false, true]);
    }
}
