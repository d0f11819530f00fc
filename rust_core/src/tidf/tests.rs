use super::*;

fn deg(a: f64) -> f64 {
    wrap_2pi(a) * 180.0 / PI
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

fn seed_search(variant: Variant) -> RootSearch {
    let s = Slider::seed();
    Tidf::new(&s, variant).find_roots(&s, &SearchOptions::default())
}

#[test]
fn jacobian_matches_finite_differences() {
    let s = Slider::seed();
    for variant in [Variant::Consistent, Variant::DeadLoad] {
        let t = Tidf::new(&s, variant);
        let x = Unknowns::new(640.0, 1.3e-6, 2.0e-5, 6.0e-6, 4.2);
        let (_, j) = t.residual_jacobian(&x);
        let h = [1e-4, 1e-12, 1e-11, 1e-12, 1e-7];
        for c in 0..5 {
            let mut xp = x;
            let mut xm = x;
            xp[c] += h[c];
            xm[c] -= h[c];
            let fd = (t.residual(&xp) - t.residual(&xm)) / (2.0 * h[c]);
            for r in 0..5 {
                let scale = j.row(r).iter().zip(h.iter()).map(|(v, h)| (v * h).abs()).fold(0.0, f64::max) / h[c];
                assert!(
                    (fd[r] - j[(r, c)]).abs() <= 1e-6 * scale.max(j[(r, c)].abs()) + 1e-12,
                    "{variant:?} J[{r},{c}] = {} fd {}",
                    j[(r, c)],
                    fd[r]
                );
            }
        }
    }
}

/// The scan's `g` alone agrees with the full closed form's over the search box and beyond it,
/// for both readings, both signs of `g` and both orientations of `(c, s)`: the scan finds the
/// same sign changes.
#[test]
fn the_scans_g_is_the_closed_forms() {
    let s = Slider::seed();
    for variant in [Variant::Consistent, Variant::DeadLoad] {
        let t = Tidf::new(&s, variant);
        let (mut pos, mut neg) = (0, 0);
        for k in 0..4000 {
            let w = 50.0 * (6000.0f64 / 50.0).powf(k as f64 / 3999.0);
            let (g, full) = (t.reduced_g(w), t.reduced(w).g);
            assert!((g - full).abs() <= 1e-12 * full.abs(), "{variant:?} w = {w}: {g} against {full}");
            (pos, neg) = (pos + usize::from(full > 0.0), neg + usize::from(full < 0.0));
        }
        assert!(pos > 100 && neg > 100, "{variant:?}: both signs of g on the grid ({pos}, {neg})");
    }
}

#[test]
fn seed_physical_root_matches_model_md() {
    let search = seed_search(Variant::Consistent);
    assert_eq!(search.status, Status::Success);
    assert_eq!(search.outcome, SearchOutcome::Roots);
    let phys: Vec<&Root> = search.roots.iter().filter(|r| r.physical).collect();
    assert_eq!(phys.len(), 1, "{:#?}", search.roots);
    let r = phys[0];
    eprintln!(
        "seed root: w {:.9} A0 {:.6e} A1 {:.6e} A2 {:.6e} theta {:.4} deg, phi1 {:.5e} at {:.3} deg, x {:.5e} at {:.3} deg, \
         z_max {:.4e}, Fz harmonics {:?}, res {:.1e}, newton {}",
        r.omega,
        r.a0,
        r.a1,
        r.a2,
        deg(r.theta),
        r.phi1_amp,
        deg(r.phi1_phase),
        r.x_amp,
        r.x_phase * 180.0 / PI,
        r.z_max,
        r.fz_harmonics,
        r.residual_norm,
        r.newton_iterations
    );
    // MODEL.md §5 "this reading" (seed_values.json tidf_root_seed), to the printed digits.
    assert!((r.omega - 647.559).abs() < 7e-4, "w = {}", r.omega);
    assert!((r.a0 - 0.958e-6).abs() < 0.6e-9, "A0 = {}", r.a0);
    assert!((r.a1 - 21.524e-6).abs() < 0.6e-9, "A1 = {}", r.a1);
    assert!((r.a2 - 5.175e-6).abs() < 0.6e-9, "A2 = {}", r.a2);
    assert!((deg(r.theta) - 251.13).abs() < 6e-3, "theta = {}", deg(r.theta));
    assert!((r.phi1_amp - 2.066e-3).abs() < 0.6e-6, "phi1 = {}", r.phi1_amp);
    assert!((deg(r.phi1_phase) - 182.42).abs() < 6e-3, "phi1 phase = {}", deg(r.phi1_phase));
    assert!((r.x_amp - 4.264e-6).abs() < 0.6e-9, "x = {}", r.x_amp);
    assert!((r.x_phase * 180.0 / PI + 0.70).abs() < 6e-3, "x phase = {}", r.x_phase * 180.0 / PI);
    // Third harmonic of K_a z^2: 2.4 N against 16.0 and 20.0 N (MODEL.md §5), to 2 %.
    assert!(rel(r.fz_harmonics[0], 16.0) < 0.02 && rel(r.fz_harmonics[1], 20.0) < 0.02, "{:?}", r.fz_harmonics);
    assert!(rel(r.fz_harmonics[2], 2.4) < 0.02, "{:?}", r.fz_harmonics);
    // The two-harmonic waveform already reaches 27.5 um > |z_st| = 16.56 um: the describing
    // function's own solution leaves the disk (the exact orbit reaches 27.8 um, MODEL.md §6).
    assert!(r.contact_opens && (r.z_max - 27.51e-6).abs() < 0.01e-6, "z_max = {}", r.z_max);
    assert!(r.residual_norm < 1e-13);
}

#[test]
fn dead_load_root_matches_model_md() {
    let search = seed_search(Variant::DeadLoad);
    let phys: Vec<&Root> = search.roots.iter().filter(|r| r.physical).collect();
    assert_eq!(phys.len(), 1);
    let r = phys[0];
    eprintln!("dead load: w {:.6} A0 {:.4e} A1 {:.5e} A2 {:.4e} theta {:.3}", r.omega, r.a0, r.a1, r.a2, deg(r.theta));
    assert!((r.omega - 647.563).abs() < 7e-4, "w = {}", r.omega);
    assert!((r.a0 - 0.978e-6).abs() < 0.6e-9, "A0 = {}", r.a0);
    assert!((r.a1 - 21.486e-6).abs() < 0.6e-9, "A1 = {}", r.a1);
    assert!((r.a2 - 5.162e-6).abs() < 0.6e-9, "A2 = {}", r.a2);
    assert!((deg(r.theta) - 251.11).abs() < 6e-3, "theta = {}", deg(r.theta));
}

#[test]
fn finer_grid_finds_the_same_roots() {
    let s = Slider::seed();
    for p in [
        Params::seed(),
        Params { normal_load: 30.0, ..Params::seed() },
        Params { mu: 0.1, normal_load: 200.0, ..Params::seed() },
    ] {
        let s2 = Slider::new(p).unwrap();
        let t = Tidf::new(&s2, Variant::Consistent);
        let base = t.find_roots(&s2, &SearchOptions::default());
        let fine = t.find_roots(&s2, &SearchOptions::default().refined(2.0));
        let finer = t.find_roots(&s2, &SearchOptions::default().refined(8.0));
        eprintln!(
            "load {} mu {}: {} roots ({} / {} / {} grid points)",
            p.normal_load,
            p.mu,
            base.roots.len(),
            base.n_grid,
            fine.n_grid,
            finer.n_grid
        );
        for r in &base.roots {
            eprintln!(
                "  w {:.4} A0 {:.3e} A1 {:.3e} A2 {:.3e} theta {:.2} physical {} opens {}",
                r.omega,
                r.a0,
                r.a1,
                r.a2,
                deg(r.theta),
                r.physical,
                r.contact_opens
            );
        }
        for other in [&fine, &finer] {
            assert_eq!(base.roots.len(), other.roots.len());
            for (a, b) in base.roots.iter().zip(other.roots.iter()) {
                assert!(rel(a.omega, b.omega) < 1e-12 && (a.a1 - b.a1).abs() < 1e-12 * s.z_st.abs(), "{a:?} {b:?}");
            }
        }
    }
}

#[test]
fn seed_has_non_physical_roots_far_from_torsion() {
    let search = seed_search(Variant::Consistent);
    let others: Vec<&Root> = search.roots.iter().filter(|r| !r.physical).collect();
    assert!(!others.is_empty());
    for r in &others {
        eprintln!("non-physical: w {:.3} A0 {:.3e} A1 {:.3e} A2 {:.3e}", r.omega, r.a0, r.a1, r.a2);
    }
    // MODEL.md §5: w about 290-600 rad/s, A0 of 100-200 um.
    assert!(others.iter().any(|r| (280.0..610.0).contains(&r.omega) && (90e-6..210e-6).contains(&r.a0.abs())));
}

#[test]
fn no_physical_root_where_sliding_is_unstable() {
    // mu = 0.215 at 15 N: below the Hopf load 24.904 N, sliding unstable (MODEL.md §4, §6).
    // MODEL.md §6 says the describing function has no root at all there. Found: no root on
    // the torsion branch (its zero has A1^2 < 0: complex amplitude), but the four far,
    // non-physical roots (w 291-585 rad/s, A0 91-176 um) exist here as at the seed.
    let p = Params { normal_load: 15.0, ..Params::seed() };
    let r = find_roots(&p, Variant::Consistent, &SearchOptions::default()).unwrap();
    assert!(r.max_growth_rate > 0.0);
    for x in &r.roots {
        eprintln!("15 N root: w {:.3} A0 {:.3e} A1 {:.3e} physical {}", x.omega, x.a0, x.a1, x.physical);
    }
    eprintln!(
        "15 N: outcome {:?}, complex-amplitude zeros {:?}, unresolved {:?}",
        r.outcome, r.complex_amplitude, r.unresolved
    );
    assert!(r.roots.iter().all(|x| !x.physical && (280.0..610.0).contains(&x.omega)));
    assert!(r.unresolved.is_empty());
    let branch: Vec<&Unresolved> = r
        .complex_amplitude
        .iter()
        .filter(|z| (z.omega - r.torsion_frequency).abs() < 0.05 * r.torsion_frequency)
        .collect();
    assert_eq!(branch.len(), 1, "{:?}", r.complex_amplitude);
    // The same holds on a load grid below the Hopf load.
    for load in [2.0, 5.0, 10.0, 20.0, 24.0] {
        let r =
            find_roots(&Params { normal_load: load, ..Params::seed() }, Variant::Consistent, &SearchOptions::default())
                .unwrap();
        assert!(r.max_growth_rate > 0.0 && r.roots.iter().all(|x| !x.physical), "load {load}");
    }
}

#[test]
fn at_the_hopf_load_the_root_is_below_resolution() {
    let p0 = Params::seed();
    let h = crate::linear::hopf_loads(&p0, 10.0, 50.0, 20).unwrap()[0];
    let p = Params { normal_load: h.normal_load, ..p0 };
    let r = find_roots(&p, Variant::Consistent, &SearchOptions::default()).unwrap();
    eprintln!(
        "at the Hopf load {}: unresolved {:?}, marginal {}, growth {:e}",
        h.normal_load, r.unresolved, r.near_marginal, r.max_growth_rate
    );
    assert!(r.near_marginal);
    assert!(r.roots.iter().all(|x| !x.physical));
    assert_eq!(r.unresolved.len(), 1);
    assert!((r.unresolved[0].omega - r.torsion_frequency).abs() < 0.01 * r.torsion_frequency);
    // Just above it, the small root is resolved and physical (subcritical: it exists on the
    // stable side); just below, the zero has A1^2 < 0 (no root).
    let above =
        find_roots(&Params { normal_load: h.normal_load * 1.01, ..p0 }, Variant::Consistent, &SearchOptions::default())
            .unwrap();
    let small: Vec<&Root> = above.roots.iter().filter(|x| x.physical).collect();
    assert_eq!(small.len(), 1);
    eprintln!("1 % above the Hopf load: A1 = {:e}", small[0].a1);
    let below =
        find_roots(&Params { normal_load: h.normal_load * 0.99, ..p0 }, Variant::Consistent, &SearchOptions::default())
            .unwrap();
    assert!(below.roots.iter().all(|x| !x.physical) && below.unresolved.is_empty());
}

#[test]
fn newton_recovers_the_root_from_a_perturbed_guess() {
    let s = Slider::seed();
    let t = Tidf::new(&s, Variant::Consistent);
    let root = seed_search(Variant::Consistent).roots.into_iter().find(|r| r.physical).unwrap();
    let guess = Unknowns::new(root.omega * 1.01, root.a0 * 1.5, root.a1 * 0.8, root.a2 * 1.2, root.theta + 0.2);
    let r = t.solve(&guess, &NewtonOptions::default());
    assert_eq!(r.status, Status::Success, "{r:?}");
    let x = canonical(&r.x);
    assert!(rel(x[0], root.omega) < 1e-13 && rel(x[2], root.a1) < 1e-10, "{x} vs {:?}", root.x);
    // A hopeless guess fails as data.
    let bad =
        t.solve(&Unknowns::new(2900.0, 1e-3, 1e-9, 1e-3, 0.0), &NewtonOptions { max_iter: 5, ..Default::default() });
    assert_ne!(bad.status, Status::Success);
}

#[test]
fn canonical_form_is_invariant() {
    let s = Slider::seed();
    let t = Tidf::new(&s, Variant::Consistent);
    let x = Unknowns::new(640.0, 1.3e-6, 2.0e-5, 6.0e-6, 4.2);
    let r0 = t.residual(&x);
    for y in [
        Unknowns::new(640.0, 1.3e-6, -2.0e-5, 6.0e-6, 4.2),
        Unknowns::new(640.0, 1.3e-6, 2.0e-5, -6.0e-6, 4.2 - PI),
        Unknowns::new(-640.0, 1.3e-6, 2.0e-5, -6.0e-6, -4.2),
    ] {
        // Re parts equal, Im parts flip with w -> -w.
        let r = t.residual(&y);
        let sign = if y[0] < 0.0 { -1.0 } else { 1.0 };
        let flip = Residual::new(r0[0], sign * r0[1], r0[2], sign * r0[3], r0[4]);
        assert!((r - flip).amax() < 1e-14, "{r} vs {flip}");
        assert!((canonical(&y) - x).amax() < 1e-14);
    }
}

#[test]
fn two_harmonic_max_is_accurate() {
    // One maximum (A2 < A1/4), and two (A2 large: the second harmonic dominates), at several phases.
    for (a0, a1, a2, th) in [
        (1e-6, 2e-5, 6e-6, 4.2),
        (-3e-6, 1e-5, 2e-6, 0.3),
        (0.0, 1e-5, 4e-5, 1.0),
        (2e-6, 5e-6, 3e-5, 5.9),
        (0.0, -1e-5, 4e-5, 3.0),
    ] {
        let brute = (0..200_000)
            .map(|i| {
                let p = 2.0 * PI * i as f64 / 200_000.0;
                a0 + a1 * p.sin() + a2 * (2.0 * p + th).sin()
            })
            .fold(f64::NEG_INFINITY, f64::max);
        let m = two_harmonic_max(a0, a1, a2, th);
        // The sampled maximum is below the true one by at most max|f''| h^2 / 8, with
        // |f''| <= |A1| + 4 |A2| and h the brute grid's spacing; both carry rounding of a few ulps.
        let h = 2.0 * PI / 200_000.0;
        let (ulps, gap) =
            (4.0 * f64::EPSILON * (a0.abs() + a1.abs() + a2.abs()), (a1.abs() + 4.0 * a2.abs()) * h * h / 8.0);
        assert!(m >= brute - ulps && m - brute <= gap + ulps, "{a1} {a2} {th}: {m} vs {brute}");
    }
}

#[test]
fn cross_check_against_a_two_dimensional_grid() {
    // Independent of the theta elimination: Newton from every node of a coarse (w, theta) grid,
    // with A0, A2 from eq k=1 and A1^2 from Re eq k=2 in closed form (MODEL.md §5's recipe).
    // Every root it converges to inside the box must be one the 1-D search found.
    for p in [Params::seed(), Params { normal_load: 30.0, ..Params::seed() }] {
        let s = Slider::new(p).unwrap();
        let t = Tidf::new(&s, Variant::Consistent);
        let search = t.find_roots(&s, &SearchOptions::default());
        let mut found = 0;
        for iw in 0..120 {
            let w = 150.0 * (20f64).powf(iw as f64 / 119.0);
            let (l1, _) = t.linear_part(1.0, w);
            let (l2, _) = t.linear_part(2.0, w);
            for it in 0..24 {
                let th = 2.0 * PI * (it as f64 + 0.5) / 24.0;
                let (sn, cs) = th.sin_cos();
                let a2 = l1.im / (t.k_a * cs);
                let a0 = (l1.re + t.k_a * a2 * sn) / (2.0 * t.k_a);
                let a1sq = 2.0 * a2 * (2.0 * t.k_a * a0 - l2.re) / (t.k_a * sn);
                if a1sq.is_nan() || a1sq <= 0.0 || a1sq.sqrt() > 1e-3 || a0.abs() > 1e-3 {
                    continue;
                }
                let r = t.solve(&Unknowns::new(w, a0, a1sq.sqrt(), a2, th), &NewtonOptions::default());
                if r.status != Status::Success {
                    continue;
                }
                let x = canonical(&r.x);
                if x[0] < 150.0 || x[0] > 3000.0 || x[2] < 1e-9 {
                    continue;
                }
                found += 1;
                assert!(
                    search.roots.iter().any(|q| rel(q.omega, x[0]) < 1e-9 && (q.a1 - x[2]).abs() < 1e-9 * s.z_st.abs()),
                    "load {}: 2-D grid root {x} not in the 1-D set",
                    p.normal_load
                );
            }
        }
        assert!(found > 0);
    }
}

#[test]
#[ignore = "timing; run with --ignored --nocapture in release"]
fn timing() {
    let s = Slider::seed();
    let t = Tidf::new(&s, Variant::Consistent);
    let opts = SearchOptions::default();
    let n = 2000;
    let t0 = std::time::Instant::now();
    let mut k = 0;
    for _ in 0..n {
        k += std::hint::black_box(t.find_roots(&s, &opts)).roots.len();
    }
    let dt = t0.elapsed().as_secs_f64() / n as f64;
    eprintln!("all-roots search: {:.1} us per point ({} roots)", dt * 1e6, k / n);
    let root = t.find_roots(&s, &opts).roots.into_iter().find(|r| r.physical).unwrap();
    let guess = Unknowns::new(root.omega * 1.001, root.a0 * 1.05, root.a1 * 0.98, root.a2 * 1.02, root.theta + 0.01);
    let m = 200_000;
    let t0 = std::time::Instant::now();
    let mut it = 0;
    for i in 0..m {
        let g = guess * (1.0 + 1e-9 * (i % 7) as f64);
        it += std::hint::black_box(t.solve(std::hint::black_box(&g), &NewtonOptions::default())).iterations;
    }
    let dt = t0.elapsed().as_secs_f64() / m as f64;
    eprintln!(
        "warm-start Newton: {:.2} us per solve, {:.0} solves/s, {:.1} iterations",
        dt * 1e6,
        1.0 / dt,
        it as f64 / m as f64
    );
}

#[test]
fn a_cancelled_grid_scan_stops_at_the_first_check() {
    // A billion base points would take minutes; cancelled, the scan stops at its first look at the
    // stop request (grid point CHECK_EVERY) with no roots and status NotComputed.
    let s = Slider::seed();
    let opts = SearchOptions { n_base: 1_000_000_000, ..SearchOptions::default() };
    let token = crate::cancel::Token::new();
    token.cancel();
    let r = token.scope(|| Tidf::new(&s, Variant::Consistent).find_roots(&s, &opts));
    assert_eq!(r.status, Status::NotComputed);
    assert_eq!(r.n_grid as u64, crate::cancel::CHECK_EVERY);
    assert!(r.roots.is_empty());
    // Uncancelled, the default grid finds the seed's roots as before.
    assert_eq!(seed_search(Variant::Consistent).status, Status::Success);
}
