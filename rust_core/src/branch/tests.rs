use super::solve::{Ctx, Seq};
use super::*;
use crate::model::{ContactMode, Params};
use crate::shooting::{shoot, ShootingOptions};

fn seed_hopf() -> (Params, f64, f64) {
    let p = Params::seed();
    let h = crate::linear::hopf_loads(&p, 1.0, 250.0, 400).unwrap();
    (p, h[0].normal_load, h[0].frequency)
}

fn unilateral_from_bouncing(dir: f64, max_points: usize) -> Branch {
    let (s, y) = crate::shooting::tests::bouncing_cycle_start();
    let o = BranchOptions { max_points, ..Default::default() };
    let start = Start::Orbit { state0: y, period: 9.81e-3, direction: dir };
    branch(&s.p, "normal_load", s.p.normal_load, start, (1.0, 150.0), &o).unwrap()
}

#[test]
fn bilateral_branch_from_the_hopf_point_reaches_the_seed_saddle_cycle() {
    let (p, fh, w) = seed_hopf();
    let b = branch(&p, "normal_load", fh, Start::Hopf { omega: w }, (fh, 84.46), &BranchOptions::default()).unwrap();
    assert_eq!(b.status, Status::Success, "{}", b.reason);
    assert!(!b.reason.is_empty());
    let (first, last) = (&b.points[1], b.points.last().unwrap());
    assert_eq!(b.points[0].point_type, PointType::Hopf);
    assert_eq!(last.point_type, PointType::End);
    assert_eq!(last.parameter, 84.46);
    // MODEL.md §6 gives the period to 7 digits: 1e-6 relative is their resolution.
    assert!((last.period / 9.702674e-3 - 1.0).abs() < 1e-6, "T = {}", last.period);
    // The moduli as MODEL.md prints them (5 digits: 1e-4 is their resolution, as in the shooting test).
    let expect = [1.00762, 1.0, 0.98883, 0.98883, 0.61117, 0.61117];
    for (m, e) in last.multipliers.iter().zip(expect) {
        assert!((m.norm() - e).abs() < 1e-4, "{:?}", last.multipliers);
    }
    // Subcritical Hopf: the cycles are born where sliding is stable (loads above 24.9 N), unstable.
    assert!(first.parameter > fh);
    let sliding = crate::linear::linear_stability_of(&Params { normal_load: first.parameter, ..p }).unwrap();
    assert!(sliding.stable && !first.stable && first.n_unstable == 1);
    // Grazing on the way: the pin first touches contact loss at 36.83 N (flagged, the bilateral law goes on).
    let g = b.points.iter().find(|q| q.point_type == PointType::Grazing).expect("a grazing point");
    assert!(g.min_gap.abs() < 1e-12 && (g.parameter - 36.83).abs() < 0.01, "{g:?}");
    assert!(last.flags & flags::OUTSIDE_BILATERAL_VALIDITY != 0);
}

#[test]
fn multipliers_agree_with_independent_shooting() {
    // Open orbits of the unilateral branch (a flight and a 0.2 ms hop per period) against today's
    // shooting, which locates its switches in one run and applies the saltation matrices. (Upwards
    // of 98.5 N the branch's orbits have hops of 33 us that today's shooting misses at its graded
    // first accuracy, 1e-7, and it converges to another orbit: not a comparison of multipliers.)
    let b = unilateral_from_bouncing(-1.0, 200);
    let so = ShootingOptions::default();
    let mut checked = 0;
    for q in b.points.iter().step_by(9).filter(|q| q.point_type == PointType::Regular) {
        let s = Slider::new(Params { normal_load: q.parameter, contact: ContactModel::Unilateral, ..Params::seed() })
            .unwrap();
        let o = shoot(&s, &q.state0, q.period, &so);
        assert_eq!(o.status, Status::Success);
        // Both solve to a scaled residual of 1e-9 at rtol 1e-11: the orbits agree to about that.
        assert!((o.period / q.period - 1.0).abs() < 1e-8, "p {} T {} vs {}", q.parameter, o.period, q.period);
        assert_eq!(o.n_switches, q.n_switches, "p {}", q.parameter);
        for (a, c) in o.multipliers.iter().zip(&q.multipliers) {
            // Eigenvalues of two monodromy matrices each accurate to about 1e-9 (the trivial
            // multiplier's error): 1e-6 leaves room for the conditioning of a non-normal matrix.
            assert!(
                (a - c).norm() < 1e-6 * c.norm().max(1.0),
                "p {}: {:?} vs {:?}",
                q.parameter,
                o.multipliers,
                q.multipliers
            );
        }
        checked += 1;
    }
    assert!(checked >= 10, "{checked}");
}

#[test]
fn segment_jacobian_matches_finite_differences() {
    // The seed bouncing cycle as 5 segments (flight, contact, hop, contact, flight).
    let (s, _) = crate::shooting::tests::bouncing_cycle_start();
    let b = unilateral_from_bouncing(1.0, 2);
    let q = b.points[0];
    assert_eq!(q.n_switches, 4);
    let o = BranchOptions::default();
    let mut ctx = Ctx {
        base: s.p,
        name: "normal_load",
        opts: o,
        sizes: crate::shooting::scales(&s),
        t_ref: q.period,
        p_ref: s.p.normal_load,
        stats: Default::default(),
        n_flows: 0,
    };
    // Sequence and durations from a run that locates the switches.
    let model = ctx.model(s.p.normal_load).unwrap();
    let fs = flow::FlowSettings { method: o.method, rtol: 1e-12, sizes: ctx.sizes, p_ref: ctx.p_ref, max_switches: 64 };
    let sw = flow::switches(&model, &q.state0, q.period, &fs, &mut Stats::default()).unwrap();
    let mut modes = vec![ContactMode::Free];
    let mut taus = vec![];
    let mut t0 = 0.0;
    for w in &sw {
        modes.push(w.after);
        taus.push(w.t - t0);
        t0 = w.t;
    }
    taus.push(q.period - t0);
    let seq = Seq { modes, events: sw.iter().map(|w| w.index).collect() };
    let xi = ctx.pack(&q.state0, &taus, s.p.normal_load);
    let (e, r0) = ctx.evaluate(&xi, &seq, 1e-12).unwrap();
    for c in 0..xi.len() {
        // Central differences of a smooth map integrated at rtol 1e-12: a step of 1e-5 (scaled)
        // keeps both truncation (h^2) and integration noise (1e-12 / h) near 1e-7.
        let h = 1e-5;
        let (mut xp, mut xm) = (xi.clone(), xi.clone());
        xp[c] += h;
        xm[c] -= h;
        let (_, rp) = ctx.evaluate(&xp, &seq, 1e-12).unwrap();
        let (_, rm) = ctx.evaluate(&xm, &seq, 1e-12).unwrap();
        for i in 0..r0.len() {
            let fd = (rp[i] - rm[i]) / (2.0 * h);
            let scale = e.jac.column(c).amax().max(1.0);
            assert!((fd - e.jac[(i, c)]).abs() < 1e-5 * scale, "d r[{i}] / d xi[{c}]: {} vs fd {fd}", e.jac[(i, c)]);
        }
    }
}

#[test]
fn a_step_that_cannot_converge_is_halved_and_ends_the_branch_with_a_reason() {
    // Two Newton steps only, and a smallest step of 0.4 (scaled): the first step, 0.5, needs
    // more, is halved to 0.25 < ds_min, and the branch ends there.
    let (s, y) = crate::shooting::tests::bouncing_cycle_start();
    let o = BranchOptions { max_newton: 2, ds: 0.5, ds_min: 0.4, ds_max: 0.5, ..Default::default() };
    let start = Start::Orbit { state0: y, period: 9.81e-3, direction: 1.0 };
    let b = branch(&s.p, "normal_load", s.p.normal_load, start, (1.0, 150.0), &o).unwrap();
    assert_eq!(b.status, Status::NewtonNotConverged, "{}", b.reason);
    assert!(b.reason.contains("halved below ds_min"), "{}", b.reason);
    assert_eq!(b.points.len(), 1);
}

#[test]
fn bad_input_is_rejected_before_any_work() {
    let (p, fh, w) = seed_hopf();
    let hopf = Start::Hopf { omega: w };
    let o = BranchOptions::default();
    let e = branch(&p, "torsion_sign", -1.0, hopf, (-2.0, 2.0), &o).unwrap_err();
    assert!(e.to_string().contains("torsion_sign"), "{e}");
    let e = branch(&p, "nope", 1.0, hopf, (0.0, 2.0), &o).unwrap_err();
    assert!(e.to_string().contains("nope"));
    let e = branch(&p, "normal_load", fh, hopf, (30.0, 40.0), &o).unwrap_err();
    assert!(e.to_string().contains("value") && e.to_string().contains("within bounds"), "{e}");
    let e = branch(&p, "normal_load", fh, Start::Hopf { omega: -1.0 }, (1.0, 40.0), &o).unwrap_err();
    assert!(e.to_string().contains("omega"), "{e}");
    let bad = BranchOptions { ds: 2.0, ..o };
    let e = branch(&p, "normal_load", fh, hopf, (1.0, 40.0), &bad).unwrap_err();
    assert!(e.to_string().contains("ds") && e.to_string().contains("2.0"), "{e}");
    let e = branch(&p, "normal_load", -5.0, hopf, (-10.0, 40.0), &o).unwrap_err();
    assert!(e.to_string().contains("normal_load"), "{e}");
}

#[test]
fn the_unilateral_branch_from_the_hopf_point_reaches_the_seed_bouncing_cycle() {
    // Hopf point -> saddle cycle -> grazing at 36.83 N (the branch turns back onto orbits with a
    // flight) -> fold near 19 N -> ... -> the stable bouncing cycle of MODEL.md §6 at the seed load.
    let (p, fh, w) = seed_hopf();
    let p = Params { contact: ContactModel::Unilateral, ..p };
    let o = BranchOptions { max_points: 3000, ..Default::default() };
    let b = branch(&p, "normal_load", fh, Start::Hopf { omega: w }, (1.0, 150.0), &o).unwrap();
    for q in b.points.iter().filter(|q| q.point_type != PointType::Regular) {
        eprintln!(
            "{:>15} {:.5} N switches {} flags {}",
            POINT_TYPE_NAMES[q.point_type as usize], q.parameter, q.n_switches, q.flags
        );
    }
    assert_eq!(b.status, Status::Success, "{}", b.reason);
    let g = b.points.iter().find(|q| q.point_type == PointType::Grazing).unwrap();
    assert!((g.parameter - 36.83).abs() < 0.01 && g.flags & flags::PARAMETER_TURNS != 0);
    assert!(b.points.iter().any(|q| q.point_type == PointType::Fold));
    // The stable stretch through the seed load: omega there (linear interpolation between the two
    // points around 84.46 N, about 0.3 N apart, where omega changes by 0.5 rad/s per N with
    // curvature below 1e-3 per N^2) against MODEL.md's 640.371 rad/s (printed to 0.001).
    let k = b
        .points
        .windows(2)
        .position(|w| w[0].stable && w[1].stable && (w[0].parameter - 84.46) * (w[1].parameter - 84.46) <= 0.0);
    let k = k.expect("a stable stretch through the seed load");
    let (a, c) = (b.points[k], b.points[k + 1]);
    let th = (84.46 - a.parameter) / (c.parameter - a.parameter);
    let omega = |q: &BranchPoint| 2.0 * std::f64::consts::PI / q.period;
    let om = omega(&a) + th * (omega(&c) - omega(&a));
    assert!((om - 640.371).abs() < 0.002, "omega {om}");
    assert_eq!(a.n_switches, 4);
}
