use super::*;
use crate::model::Params;
use crate::ode::lanes::exp_lanes_by;
use crate::ode::Method;
use crate::steady::run;

/// The benchmark ensemble of issue 2 (seed configuration, `mu` in [0.15, 0.30], load in
/// [17, 152] N, z0 = 1 um), from a fixed linear congruential generator.
fn ensemble(n: usize, seed: u64) -> (Vec<Slider>, Vec<State>) {
    let mut x = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
    let mut u = || {
        x = x.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (x >> 11) as f64 / (1u64 << 53) as f64
    };
    let mut s = Vec::with_capacity(n);
    for _ in 0..n {
        let mu = 0.15 + 0.15 * u();
        let normal_load = 17.0 + 135.0 * u();
        s.push(Slider::new(Params { mu, normal_load, ..Params::seed() }).unwrap());
    }
    let y0 = vec![State::new(1e-6, 0.0, 0.0, 0.0, 0.0, 0.0); n];
    (s, y0)
}

impl<'a> Job<'a> {
    /// The end states of `sliders` from `y0s`, no samples.
    fn end_states(sliders: &'a [Slider], y0s: &'a [State], t_end: f64, tol: &'a Tolerances) -> Self {
        Job { sliders, y0s, t_end, tol, t_eval: &[], samples: &mut [], counts: &mut [] }
    }
}

fn tol(rtol: f64) -> Tolerances {
    Tolerances::new(rtol)
}

fn same(a: &RunResult, b: &RunResult) -> bool {
    let bits = |r: &RunResult| {
        let mut v: Vec<u64> = r.y.iter().map(|x| x.to_bits()).collect();
        v.push(r.t.to_bits());
        let e = r.extremes;
        v.extend([e.min_normal_force, e.max_gap, e.min_slip_velocity, e.max_abs_z].map(f64::to_bits));
        v.extend([r.stats.n_rhs, r.stats.n_accept, r.stats.n_reject]);
        v
    };
    a.status == b.status && bits(a) == bits(b)
}

#[test]
fn lane_exp_and_ln() {
    let mut worst = (0.0f64, 0.0f64);
    let mut x: f64 = 1e-300;
    while x < 1e300 {
        let v = [x, 1.0 / x, 0.7 * x, 1.3 * x, x.sqrt(), 1.0, 0.5, 2.0];
        let l = ln_lanes(&v);
        for k in 0..W {
            worst.0 = worst.0.max((l[k] - v[k].ln()).abs() / v[k].ln().abs().max(1.0));
        }
        x *= 1.37;
    }
    let mut a: f64 = -700.0;
    while a < 700.0 {
        let v = [a, -a, 0.5 * a, 1e-3 * a, 0.0, 1e-17, a + 0.3, -0.1];
        let e = exp_lanes(&v);
        let es = exp_lanes_by::<true, W>(&v);
        for k in 0..W {
            worst.1 = worst.1.max((e[k] - v[k].exp()).abs() / v[k].exp());
            worst.1 = worst.1.max((es[k] - v[k].exp()).abs() / v[k].exp());
        }
        a += 0.913;
    }
    assert!(worst.0 < 1e-15 && worst.1 < 2e-15, "{worst:?}");
}

#[test]
fn agrees_with_the_scalar_path() {
    let (s, y0) = ensemble(50, 1);
    let t_end = 0.5;
    let refs: Vec<RunResult> = s.iter().zip(&y0).map(|(s, y)| run(s, y, t_end, Method::Dop853, &tol(1e-13))).collect();
    for (m, rtol) in [(Method::Dopri5, 1e-6), (Method::Dopri5, 1e-9), (Method::Dop853, 1e-6), (Method::Dop853, 1e-9)] {
        let b = run_bilateral_batch(&s, &y0, t_end, m, &tol(rtol));
        let (mut worst, mut steps_b, mut steps_s) = (0.0f64, 0u64, 0u64);
        for i in 0..s.len() {
            let sc = run(&s[i], &y0[i], t_end, m, &tol(rtol));
            let r = &refs[i];
            assert_eq!(r.status, Status::Success);
            assert_eq!(sc.status, Status::Success);
            assert_eq!(b[i].status, Status::Success, "{i}");
            assert_eq!(b[i].t, t_end);
            let scale = r.extremes.max_abs_z;
            let e_s = (sc.y[0] - r.y[0]).abs();
            let e_b = (b[i].y[0] - r.y[0]).abs();
            assert!(e_b <= 10.0 * e_s + 1e-3 * rtol * scale, "rtol {rtol} #{i}: batch error {e_b:e}, scalar {e_s:e}");
            worst = worst.max(e_b / scale);
            for c in 0..6 {
                let size = characteristic_sizes(&s[i])[c];
                assert!((b[i].y[c] - sc.y[c]).abs() <= 1e3 * rtol * size.max(r.y[c].abs()), "rtol {rtol} #{i} y[{c}]");
            }
            let (nb, ns) = (b[i].stats.n_accept + b[i].stats.n_reject, sc.stats.n_accept + sc.stats.n_reject);
            assert!((nb as f64 - ns as f64).abs() <= 0.03 * ns as f64 + 2.0, "#{i}: {nb} vs {ns} steps");
            // DP5: six new stages per attempt; DOP853: eleven, and the derivative at each
            // accepted step's end (the scalar driver's count).
            let work = if m == Method::Dop853 { 11 * nb + b[i].stats.n_accept } else { 6 * nb };
            assert_eq!(b[i].stats.n_rhs, 2 + work);
            let (eb, es) = (b[i].extremes, sc.extremes);
            assert!((eb.max_abs_z - es.max_abs_z).abs() <= 1e-3 * es.max_abs_z);
            assert!((eb.min_normal_force - es.min_normal_force).abs() <= 1e-3 * s[i].p.normal_load);
            assert!((eb.max_gap - es.max_gap).abs() <= 1e-3 * es.max_abs_z);
            assert!((eb.min_slip_velocity - es.min_slip_velocity).abs() <= 1e-3 * s[i].p.sliding_speed);
            steps_b += nb;
            steps_s += ns;
        }
        println!("{m:?} rtol {rtol:e}: max |z - z_ref|/max|z| = {worst:.2e}; steps batch {steps_b}, scalar {steps_s}");
    }
}

#[test]
fn results_do_not_depend_on_the_batch() {
    for m in [Method::Dopri5, Method::Dop853] {
        independent_of_the_batch(m);
    }
}

fn independent_of_the_batch(m: Method) {
    let (s, y0) = ensemble(37, 2);
    let t = tol(1e-7);
    let all = run_bilateral_batch(&s, &y0, 0.2, m, &t);
    // Each alone.
    for i in (0..s.len()).step_by(5) {
        let one = run_bilateral_batch(&s[i..i + 1], &y0[i..i + 1], 0.2, m, &t);
        assert!(same(&one[0], &all[i]), "#{i} alone");
    }
    // Permuted and in other groupings.
    let perm: Vec<usize> = (0..s.len()).map(|k| (k * 11 + 3) % s.len()).collect();
    let sp: Vec<Slider> = perm.iter().map(|&k| s[k]).collect();
    let yp: Vec<State> = perm.iter().map(|&k| y0[k]).collect();
    let rp = run_bilateral_batch(&sp, &yp, 0.2, m, &t);
    for (j, &k) in perm.iter().enumerate() {
        assert!(same(&rp[j], &all[k]), "permuted #{k}");
    }
    for chunk in [3, 8, 13] {
        let mut k = 0;
        for (cs, cy) in s.chunks(chunk).zip(y0.chunks(chunk)) {
            for r in run_bilateral_batch(cs, cy, 0.2, m, &t) {
                assert!(same(&r, &all[k]), "chunk {chunk} #{k}");
                k += 1;
            }
        }
    }
    // The portable code path, at 8 lanes and at the AVX-512 copy's 16, gives the same bits as
    // the SIMD copy picked at run time: a lane's arithmetic does not depend on the lane count.
    let (job, m8) = (|| Job::end_states(&s, &y0, 0.2, &t), m == Method::Dop853);
    let portable = if m8 { run_impl::<true, W>(job()) } else { run_impl::<false, W>(job()) };
    let wide = if m8 { run_impl::<true, W_AVX512>(job()) } else { run_impl::<false, W_AVX512>(job()) };
    for i in 0..s.len() {
        assert!(same(&portable[i], &all[i]), "{m:?} portable #{i}");
        assert!(same(&wide[i], &all[i]), "{m:?} portable, {W_AVX512} lanes #{i}");
    }
}

/// Samples at `t_eval`: the scalar `run_sampled`'s to the paths' rounding-level differences (the
/// same steps on most trajectories, the same interpolant formula), one per time; the escaping run's
/// stop at the located crossing; independent of the batch bit for bit.
#[test]
fn samples_agree_with_the_scalar_path() {
    for m in [Method::Dopri5, Method::Dop853] {
        let (mut sl, mut ys) = ensemble(19, 5);
        // One that escapes (before 20 s), in the middle of the batch.
        sl.insert(9, Slider::new(Params { mu: 0.35, normal_load: 84.46, ..Params::seed() }).unwrap());
        ys.insert(9, State::new(1e-6, 0.0, 0.0, 0.0, 0.0, 0.0));
        let t_end = 20.0;
        let te: Vec<f64> = (0..=2000).map(|j| t_end * j as f64 / 2000.0).collect();
        let r = run_bilateral_batch_sampled(&sl, &ys, t_end, m, &tol(1e-6), &te);
        let (mut worst, mut escaped) = (0.0f64, 0);
        for (i, (run, samples)) in r.iter().enumerate() {
            let (sc, ss) = crate::steady::run_sampled(&sl[i], &ys[i], t_end, m, &tol(1e-6), &te);
            assert_eq!(run.status, sc.status, "{m:?} #{i}");
            assert_eq!(samples.len(), te.len(), "{m:?} #{i}");
            // Samples up to the end of the run (for an escape, the located crossing), NaN after it,
            // as the scalar path's.
            let reached = samples.iter().take_while(|x| x[0].is_finite()).count();
            let reached_sc = ss.iter().take_while(|x| x[0].is_finite()).count();
            assert_eq!(reached, reached_sc, "{m:?} #{i}");
            assert!(te[reached - 1] <= run.t && samples[reached..].iter().all(|x| x.iter().all(|v| v.is_nan())));
            escaped += (run.status == Status::Diverged) as usize;
            assert_eq!(samples[0], ys[i], "{m:?} #{i}: t = 0 is the start");
            let scale = run.extremes.max_abs_z;
            // Each path held to its own distance from a tight reference (as the end-state test):
            // the two differ by rounding per step, amplified along growing runs.
            let (_, rf) = crate::steady::run_sampled(&sl[i], &ys[i], t_end, Method::Dop853, &tol(1e-12), &te);
            let (mut e_b, mut e_s) = (0.0f64, 0.0f64);
            for ((a, b), c) in samples.iter().zip(&ss).zip(&rf).take(reached.min(reached_sc) - 1) {
                e_b = e_b.max((a[0] - c[0]).abs() / scale);
                e_s = e_s.max((b[0] - c[0]).abs() / scale);
            }
            assert!(e_b <= 10.0 * e_s + 1e-5, "{m:?} #{i}: batch {e_b:e}, scalar {e_s:e}");
            worst = worst.max(e_b);
        }
        assert!(r[9].0.status == Status::Diverged && escaped < r.len(), "{m:?}: {escaped} escaped");
        println!("{m:?}: largest sample error against rtol 1e-12, batch {worst:.2e} (growing runs over 20 s)");
        // The batch's composition does not matter.
        let (rev_s, rev_y): (Vec<Slider>, Vec<State>) = sl.iter().copied().zip(ys.iter().copied()).rev().unzip();
        let rr = run_bilateral_batch_sampled(&rev_s, &rev_y, t_end, m, &tol(1e-6), &te);
        for (i, (run, samples)) in r.iter().enumerate() {
            let (run2, samples2) = &rr[r.len() - 1 - i];
            assert!(same(run, run2), "{m:?} #{i}");
            let bits = |v: &Vec<State>| {
                v.iter().flat_map(|x| x.iter().map(|c| c.to_bits()).collect::<Vec<_>>()).collect::<Vec<_>>()
            };
            assert_eq!(bits(samples), bits(samples2), "{m:?} #{i}");
        }
    }
}

#[test]
fn escape_stops_with_diverged() {
    for m in [Method::Dopri5, Method::Dop853] {
        escape_is_located(m);
    }
}

fn escape_is_located(m: Method) {
    let s = Slider::new(Params { mu: 0.35, normal_load: 84.46, ..Params::seed() }).unwrap();
    let y0 = State::new(1e-6, 0.0, 0.0, 0.0, 0.0, 0.0);
    let (ens, ey) = ensemble(5, 3);
    let mut sl = ens.clone();
    let mut ys = ey.clone();
    sl.insert(2, s);
    ys.insert(2, y0);
    let r = run_bilateral_batch(&sl, &ys, 20.0, m, &tol(1e-6));
    let d = &r[2];
    assert_eq!(d.status, Status::Diverged);
    assert!(d.y[0].abs() >= s.p.escape_limit && d.extremes.max_abs_z >= s.p.escape_limit);
    assert!(d.t < 20.0 && d.y.iter().all(|v| v.is_finite()));
    let sc = run(&s, &y0, 20.0, m, &tol(1e-6));
    assert_eq!(sc.status, Status::Diverged);
    // The escape is located inside the step, as the scalar path's event: the same time and
    // state to the paths' rounding-level differences (amplified over a growing run).
    eprintln!("batch t {:.15e} z {:.6e}; scalar t {:.15e} z {:.6e}", d.t, d.y[0], sc.t, sc.y[0]);
    assert!((d.t - sc.t).abs() < 1e-9 * sc.t, "{} vs {}", d.t, sc.t);
    assert!((d.y[0].abs() / s.p.escape_limit - 1.0) < 1e-9, "{}", d.y[0]);
    assert!((d.y - sc.y).amax() < 1e-6 * sc.y.amax(), "{} vs {}", d.y, sc.y);
    assert_eq!(d.stats.n_accept, sc.stats.n_accept);
    assert!((d.extremes.max_abs_z - sc.extremes.max_abs_z).abs() < 1e-12, "{:?} vs {:?}", d.extremes, sc.extremes);
    for (i, x) in r.iter().enumerate() {
        assert!(x.y.iter().all(|v| v.is_finite()), "#{i}");
        if i != 2 {
            assert_eq!(x.status, Status::Success);
            assert_eq!(x.t, 20.0);
        }
    }
}

#[test]
fn failures_and_trivial_runs() {
    for m in [Method::Dopri5, Method::Dop853] {
        failures(m);
    }
}

fn failures(m: Method) {
    let (s, mut y0) = ensemble(4, 4);
    y0[1][3] = f64::NAN;
    let r = run_bilateral_batch(&s, &y0, 0.1, m, &tol(1e-6));
    assert_eq!(r[1].status, Status::NonFinite);
    assert!([0, 2, 3].iter().all(|&i| r[i].status == Status::Success && r[i].t == 0.1));
    let r = run_bilateral_batch(&s[..1], &y0[..1], 0.0, m, &tol(1e-6));
    assert_eq!((r[0].status, r[0].stats.n_rhs), (Status::Success, 0));
    assert!(run_bilateral_batch(&[], &[], 1.0, m, &tol(1e-6)).is_empty());
    // Past the escape limit the quadratic contact law blows up in finite time: both paths end
    // with the same failure, never with NaN in the state.
    let s = Slider::new(Params { mu: 0.35, escape_limit: 1e300, ..Params::seed() }).unwrap();
    let y0 = State::new(1e-6, 0.0, 0.0, 0.0, 0.0, 0.0);
    let r = run_bilateral_batch(&[s], &[y0], 20.0, m, &tol(1e-6));
    let sc = run(&s, &y0, 20.0, m, &tol(1e-6));
    println!("{:?} {:?} {:?} | {:?} {:?} {:?}", r[0].status, r[0].t, r[0].stats, sc.status, sc.t, sc.stats);
    assert_eq!(r[0].status, sc.status);
    assert!(r[0].status != Status::Success && (r[0].t - sc.t).abs() < 1e-3 * sc.t);
}

/// One path alone, for `perf stat` (cycles do not count the time other processes hold the
/// core): `BATCH_PATH=batch|scalar|portable BATCH_RTOL=1e-6 ... batch::tests::one_path -- --ignored`.
#[test]
#[ignore]
fn one_path() {
    let n = 1000;
    let (s, y0) = ensemble(n, 7);
    let rtol: f64 = std::env::var("BATCH_RTOL").ok().and_then(|v| v.parse().ok()).unwrap_or(1e-6);
    let t = tol(rtol);
    let path = std::env::var("BATCH_PATH").unwrap_or_else(|_| "batch".into());
    for _ in 0..5 {
        match path.as_str() {
            "scalar" => {
                for i in 0..n {
                    std::hint::black_box(run(&s[i], &y0[i], 0.5, Method::Dopri5, &t));
                }
            }
            "portable" => {
                std::hint::black_box(run_impl::<false, W>(Job::end_states(&s, &y0, 0.5, &t)));
            }
            _ => {
                std::hint::black_box(run_bilateral_batch(&s, &y0, 0.5, Method::Dopri5, &t));
            }
        }
    }
}

/// Throughput against the lane route and the scalar driver in the same process (single thread;
/// the four are interleaved and the best of five taken, against a noisy machine), both methods:
/// `cargo test --profile release -p tribosweep-core batch::tests::throughput -- --ignored --nocapture`.
#[test]
#[ignore]
fn throughput() {
    use crate::ensemble::lanes::run_lanes;
    use crate::ensemble::Task;
    use std::time::Instant;
    let n = 1000;
    let (s, y0) = ensemble(n, 7);
    for (m, rtol) in [(Method::Dopri5, 1e-6), (Method::Dop853, 1e-6), (Method::Dopri5, 1e-9), (Method::Dop853, 1e-9)] {
        let t = tol(rtol);
        let time = |f: &dyn Fn()| {
            let t0 = Instant::now();
            f();
            t0.elapsed().as_secs_f64()
        };
        let portable = |t: &Tolerances| {
            if m == Method::Dop853 {
                run_impl::<true, W>(Job::end_states(&s, &y0, 0.5, t))
            } else {
                run_impl::<false, W>(Job::end_states(&s, &y0, 0.5, t))
            }
        };
        let mut best = [f64::INFINITY; 4];
        for _ in 0..5 {
            best[0] = best[0].min(time(&|| {
                std::hint::black_box(run_bilateral_batch(&s, &y0, 0.5, m, &t));
            }));
            best[1] = best[1].min(time(&|| {
                for i in 0..n {
                    std::hint::black_box(run(&s[i], &y0[i], 0.5, m, &t));
                }
            }));
            best[2] = best[2].min(time(&|| {
                std::hint::black_box(portable(&t));
            }));
            best[3] = best[3].min(time(&|| {
                std::hint::black_box(run_lanes(&s, &y0, 0.5, m, &t, Task::Final));
            }));
        }
        let r = run_bilateral_batch(&s, &y0, 0.5, m, &t);
        let steps: u64 = r.iter().map(|x| x.stats.n_accept + x.stats.n_reject).sum();
        println!(
            "{m:?} rtol {rtol:e}: batch {:.0} traj/s, scalar steady::run {:.0} traj/s ({:.2}x), lanes {:.0} traj/s \
             ({:.2}x), portable (no AVX) batch {:.0} traj/s; {:.0} steps/traj, {:.1} ns/step/traj",
            n as f64 / best[0],
            n as f64 / best[1],
            best[1] / best[0],
            n as f64 / best[3],
            best[3] / best[0],
            n as f64 / best[2],
            steps as f64 / n as f64,
            best[0] / steps as f64 * 1e9
        );
    }
}
