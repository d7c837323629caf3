//! The report's summary readings of an error-against-run-time curve
//! (`reference::curve`): interpolation in log-log, crossings, budgets, and bad points.

use bevy_caustics::reference::curve::{Reach, error_within, ms_to_reach};

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-9 * b.abs().max(1.0)
}

#[test]
fn ms_to_reach_interpolates_in_log_log() {
    // 10 ms at 0.1, 1000 ms at 0.001: a straight line in log-log, slope -1, so 0.01 at 100 ms.
    let curve = [(1000.0, 0.001), (10.0, 0.1)];
    match ms_to_reach(&curve, 0.01) {
        Reach::At(ms) => assert!(close(ms, 100.0), "{ms}"),
        r => panic!("{r:?}"),
    }
    // The cheapest point already reaches it: at most its run time.
    assert_eq!(ms_to_reach(&curve, 0.5), Reach::AtMost(10.0));
    assert_eq!(ms_to_reach(&curve, 0.1), Reach::AtMost(10.0));
    // Exactly at the second point.
    match ms_to_reach(&curve, 0.001) {
        Reach::At(ms) => assert!(close(ms, 1000.0), "{ms}"),
        r => panic!("{r:?}"),
    }
    assert_eq!(ms_to_reach(&curve, 1e-4), Reach::NotReached);
    // The first crossing counts, even where the curve rises again afterwards.
    let bumpy = [(1.0, 0.2), (2.0, 0.04), (4.0, 0.08), (8.0, 0.01)];
    match ms_to_reach(&bumpy, 0.05) {
        Reach::At(ms) => assert!(ms > 1.0 && ms < 2.0, "{ms}"),
        r => panic!("{r:?}"),
    }
}

#[test]
fn error_within_budget() {
    let curve = [(10.0, 0.1), (1000.0, 0.001)];
    assert_eq!(error_within(&curve, 5.0), None, "over budget");
    assert!(close(error_within(&curve, 10.0).unwrap(), 0.1));
    assert!(close(error_within(&curve, 100.0).unwrap(), 0.01));
    assert!(
        close(error_within(&curve, 1e6).unwrap(), 0.001),
        "beyond the last point"
    );
    // A cheaper point better than the interpolation at the budget wins.
    let bumpy = [(1.0, 0.02), (10.0, 0.5), (100.0, 0.005)];
    assert!(close(error_within(&bumpy, 5.0).unwrap(), 0.02));
}

#[test]
fn bad_points_are_left_out() {
    let curve = [
        (f64::NAN, 0.01),
        (0.0, 0.01),
        (10.0, f64::INFINITY),
        (20.0, 0.0),
        (-1.0, 0.5),
        (40.0, 0.2),
    ];
    assert_eq!(ms_to_reach(&curve, 0.3), Reach::AtMost(40.0));
    assert_eq!(error_within(&curve, 30.0), None);
    assert_eq!(ms_to_reach(&[], 0.05), Reach::NotReached);
    assert_eq!(error_within(&[], 100.0), None);
    // No caustic: error 0 everywhere, nothing to read.
    assert_eq!(
        ms_to_reach(&[(1.0, 0.0), (2.0, 0.0)], 0.05),
        Reach::NotReached
    );
    assert_eq!(ms_to_reach(&curve, f64::NAN), Reach::NotReached);
    assert_eq!(ms_to_reach(&curve, 0.0), Reach::NotReached);
}
