use super::*;
use crate::model::Params;

#[test]
fn amp_phase_convention() {
    // 2 sin(x + 0.3) = 2 sin 0.3 cos x + 2 cos 0.3 sin x
    let (a, b) = (2.0 * 0.3f64.sin(), 2.0 * 0.3f64.cos());
    let (amp, ph) = amp_phase(a, b);
    assert!((amp - 2.0).abs() < 1e-15 && (ph - 0.3).abs() < 1e-15);
    assert!((wrap(-0.1) - (std::f64::consts::TAU - 0.1)).abs() < 1e-15);
}

#[test]
fn characteristic_sizes_follow_static_point() {
    let s = Slider::seed();
    let c = characteristic_sizes(&s);
    assert!((c[0] - 16.5612e-6).abs() < 1e-10);
    assert!((c[4] - 16.5612e-6 / 0.065).abs() < 1e-8);
    let _ = Params::seed();
}

#[test]
fn x_is_left_out_of_the_settling_tests_only_where_it_is_slaved() {
    let off = SteadyOptions { watch_x: false, ..SteadyOptions::default() };
    let constant = Slider::seed();
    assert_eq!(SectionWatcher::new(&off, &constant).comps, &NOT_X[..]);
    assert_eq!(SectionWatcher::new(&SteadyOptions::default(), &constant).comps, &ALL[..]);
    // Speed-dependent friction: x acts back through the sliding velocity, so it is always watched.
    for law in [FrictionLaw::Coulomb, FrictionLaw::Switch] {
        let s = Slider::new(Params { friction_law: law, mu_static: 0.3, ..Params::seed() }).unwrap();
        assert_eq!(SectionWatcher::new(&off, &s).comps, &ALL[..], "{law:?}");
    }
}

#[test]
fn checked_stops_hold_x_to_a_looser_repetition_and_only_x() {
    // A period-1 cycle whose x alone still rings down by `mu` a section from `a` times its size
    // (the friction mode under a speed-dependent law: mu about 0.993). Relative to its amplitude
    // (which includes the deviation), x repeats to (1 - mu) a r / (1 + a r), r = mu^n: the first
    // section where that is within `tol`, before the two matches in a row.
    let sizes = characteristic_sizes(&Slider::seed());
    let ring = |c: usize, a: f64, mu: f64| {
        move |n: usize| {
            let mut y = State::from_fn(|k, _| sizes[k]);
            y[c] += a * mu.powi(n as i32) * sizes[c];
            y
        }
    };
    let first = |a: f64, mu: f64, tol: f64| ((tol / (a * (1.0 - mu - tol))).ln() / mu.ln()).ceil() as usize;
    let tol = 1e-3;
    let strict = SteadyOptions { periodic_tol: tol, ..SteadyOptions::default() };
    let checked = SteadyOptions { checked_stops: true, ..strict };
    let stop = |o: &SteadyOptions, y| {
        let (what, n) = watch(o, 3000, y);
        assert_eq!(what, "periodic");
        n
    };
    // Held to the tolerance, the stop waits for the slow ring-down (some 260 sections).
    let n = stop(&strict, ring(idx::X, 1.0, 0.993));
    assert!(n.abs_diff(first(1.0, 0.993, tol)) <= 4 && n > 200, "{n} against {}", first(1.0, 0.993, tol));
    // Checked stops hold x to CHECKED_X_SLACK times the tolerance: a ring-down slower than 1 % a
    // section does not hold them back at all ...
    assert!(stop(&checked, ring(idx::X, 1.0, 0.993)) <= 8);
    // ... a faster change of x does (5 % a section: 27 sections against 76).
    let slack = CHECKED_X_SLACK * tol;
    let n = stop(&checked, ring(idx::X, 1.0, 0.95));
    assert!(n.abs_diff(first(1.0, 0.95, slack)) <= 4 && n > 20, "{n} against {}", first(1.0, 0.95, slack));
    let n = stop(&strict, ring(idx::X, 1.0, 0.95));
    assert!(n.abs_diff(first(1.0, 0.95, tol)) <= 4, "{n} against {}", first(1.0, 0.95, tol));
    // The other components keep the tolerance: the same ring-down in z or phi is not let off.
    for c in [idx::Z, idx::PHI] {
        assert_eq!(stop(&strict, ring(c, 1.0, 0.993)), stop(&checked, ring(c, 1.0, 0.993)));
    }
}

#[test]
fn per_component_decay_thresholds_set_the_decay_test() {
    // A small torsion-mode motion of the seed (sliding stable, decaying at 0.33 1/s).
    let s = Slider::seed();
    let y0 = State::new(1e-6, 0.0, 0.0, 0.0, 1e-4, 0.0);
    let sizes = characteristic_sizes(&s);
    let d = 1e-2 * s.z_st.abs();
    let base = SteadyOptions { t_max: 60.0, ..SteadyOptions::default() };
    let plain = run_to_steady(&s, &y0, &SteadyOptions { decay_amplitude: Some(d), ..base });
    // Thresholds in the shape of the characteristic sizes are the same test.
    let same = sizes.map(|c| c * d / sizes[0]);
    let shaped = run_to_steady(&s, &y0, &DecayTest::Thresholds(same).apply(&base));
    assert_eq!(plain.outcome, SteadyOutcome::Decayed);
    assert_eq!(shaped.outcome, SteadyOutcome::Decayed);
    assert_eq!(plain.t_end, shaped.t_end);
    // The torsion motion dominates the measure (phi is 1e-4 rad against |z_st|/L = 2.5e-4 rad for
    // z = 1e-6 m against 1.7e-5 m): thresholds 10x larger in phi and phid alone stop it earlier,
    // by about ln(10) / 0.33 = 7 s.
    let mut wide = same;
    wide[idx::PHI] *= 10.0;
    wide[idx::PHID] *= 10.0;
    let early = run_to_steady(&s, &y0, &DecayTest::Thresholds(wide).apply(&base));
    assert_eq!(early.outcome, SteadyOutcome::Decayed);
    assert!(early.t_end < plain.t_end - 5.0, "{} vs {}", early.t_end, plain.t_end);
    // An amplitude override replaces thresholds.
    let back = DecayTest::Amplitude(d).apply(&DecayTest::Thresholds(wide).apply(&base));
    assert_eq!(back.decay_thresholds, None);
    assert_eq!(run_to_steady(&s, &y0, &back).t_end, plain.t_end);
}

/// Feed the watcher section states `y(n)` at times `n * dt` until it decides (or `n_max`), and say
/// what it decided and after how many sections.
fn watch(opts: &SteadyOptions, n_max: usize, y: impl Fn(usize) -> State) -> (&'static str, usize) {
    let (w, n) = watcher(opts, n_max, y);
    let what = if w.found.is_some() {
        "periodic"
    } else if w.decayed {
        "decayed"
    } else if w.irregular {
        "irregular"
    } else {
        "running"
    };
    (what, n)
}

/// [`watch`]'s watcher once it decided (or after `n_max` sections), and the sections it saw.
fn watcher(opts: &SteadyOptions, n_max: usize, y: impl Fn(usize) -> State) -> (SectionWatcher, usize) {
    let s = Slider::seed();
    let mut w = SectionWatcher::new(opts, &s);
    for n in 0..n_max {
        let c = y(n);
        w.push(Crossing { t: 0.01 * n as f64, y: c, peaks: c.abs() });
        if w.found.is_some() || w.decayed || w.irregular {
            return (w, n + 1);
        }
    }
    (w, n_max)
}

/// A section state of the seed's sizes that never repeats: two incommensurate phases (a
/// quasi-periodic torus) of amplitude `amp`.
fn torus(amp: f64) -> impl Fn(usize) -> State {
    let sizes = characteristic_sizes(&Slider::seed());
    move |n: usize| {
        let (a, b) = (n as f64 * 0.618_033_988_749_895, n as f64 * 0.414_213_562_373_095);
        let (a, b) = (std::f64::consts::TAU * a, std::f64::consts::TAU * b);
        let mut y = State::zeros();
        for (c, v) in [(0, 1.0 + 0.2 * a.cos()), (2, 0.3 * b.sin()), (4, 1.0 + 0.2 * b.cos()), (5, 0.5 * a.sin())] {
            y[c] = amp * v * sizes[c];
        }
        y
    }
}

/// Section states converging on a period-2 cycle, spread over two points, with a residual
/// shrinking by `mult` per section.
fn two(mult: f64) -> impl Fn(usize) -> State {
    let sizes = characteristic_sizes(&Slider::seed());
    move |n: usize| {
        let sign = if n.is_multiple_of(2) { 1.0 } else { -1.0 };
        State::from_fn(|c, _| sizes[c] * (1.0 + 0.3 * sign)) + mult.powi(n as i32) * torus(0.1)(n)
    }
}

#[test]
fn stationary_irregular_motion_stops_after_three_blocks_and_nothing_else_does() {
    let opts = SteadyOptions { watch_x: false, irregular_block: 32, ..SteadyOptions::default() };
    // Blocks start once 8 states are there to compare with (the 9th); three full blocks later it stops.
    assert_eq!(watch(&opts, 1000, torus(1.0)), ("irregular", 8 + 3 * 32));
    // Off by default: the same motion runs on.
    assert_eq!(watch(&SteadyOptions { watch_x: false, ..SteadyOptions::default() }, 1000, torus(1.0)).0, "running");
    // Growing by 0.2 % per section (13 % per two blocks): never stationary.
    assert_eq!(watch(&opts, 1000, |n| torus(1.002f64.powi(n as i32))(n)).0, "running");
    // Converging on a period-2 cycle at 0.9: recognised as periodic, never taken for irregular on the way.
    let (what, n) = watch(&opts, 1000, two(0.9));
    assert_eq!(what, "periodic", "after {n}");
    // At 0.99 (47 % per two blocks) still not irregular: it waits for the repetition test.
    assert_ne!(watch(&opts, 3000, two(0.99)).0, "irregular");
    // A converged cycle whose section states jitter at 1e-6 of the sizes (integration error)
    // never repeats to a periodic_tol of 1e-15, and its residual is as steady as a torus's; the
    // floor of 1e-3 keeps it from passing for irregular motion.
    let tight = SteadyOptions { periodic_tol: 1e-15, ..opts };
    let jitter = |n: usize| two(0.0)(n) + 1e-5 * torus(1.0)(n);
    assert_eq!(watch(&tight, 3000, jitter), ("running", 3000));
}

#[test]
fn a_loose_periodic_tol_keeps_the_stationarity_floor_of_stationary_tol() {
    // A period-2 cycle with a torus of 2 % of the sizes on top: a residual of some 5e-3 of the
    // sizes, steady, and never a repetition to 1e-3 of the amplitudes.
    let opts = SteadyOptions { watch_x: false, irregular_block: 32, ..SteadyOptions::default() };
    let wobble = |n: usize| two(0.0)(n) + 0.02 * torus(1.0)(n);
    assert_eq!(watch(&opts, 1000, wobble), ("irregular", 8 + 3 * 32));
    // A loose periodic_tol alone raises the floor to 100 times itself (0.1): the same motion runs on.
    let loose = SteadyOptions { periodic_tol: 1e-3, ..opts };
    assert_eq!(watch(&loose, 1000, wobble), ("running", 1000));
    // With the strict tolerance's floor kept, it is irregular after the same sections.
    let kept = SteadyOptions { stationary_tol: Some(1e-5), ..loose };
    assert_eq!(watch(&kept, 1000, wobble), ("irregular", 8 + 3 * 32));
    // ...and the loose tolerance still stops a cycle approached at 0.9 per section, sooner.
    let (strict_n, loose_n) = (watch(&opts, 1000, two(0.9)), watch(&kept, 1000, two(0.9)));
    assert_eq!((strict_n.0, loose_n.0), ("periodic", "periodic"));
    assert!(loose_n.1 < strict_n.1, "{loose_n:?} {strict_n:?}");
}

/// Independent draws with an exponential tail (`P(X > k)` about `2^-k`): the leading zero bits of
/// a hashed `n` (splitmix64) plus a uniform fraction from a second hash. Integer arithmetic only:
/// the same bits on every machine.
fn heavy(n: usize) -> f64 {
    let mix = |k: u64| {
        let mut z = k.wrapping_add(1).wrapping_mul(0x9E37_79B9_7F4A_7C15);
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    };
    let n = n as u64;
    mix(n).leading_zeros() as f64 + (mix(n + (1 << 32)) >> 11) as f64 / (1u64 << 53) as f64
}

/// Chaotic-like section states: the torus with its amplitude scaled per section by `1 + 0.05 X_n`
/// ([`heavy`]), and grown by `growth` per section.
fn noisy(growth: f64) -> impl Fn(usize) -> State {
    move |n: usize| torus(1.0)(n) * ((1.0 + 0.05 * heavy(n)) * (1.0 + growth).powi(n as i32))
}

#[test]
fn fluctuating_excursions_pass_by_their_trend_and_a_drift_under_them_does_not() {
    let opts = SteadyOptions { watch_x: false, irregular_block: 256, ..SteadyOptions::default() };
    // The largest z excursion of each of the first three blocks spreads by 8 %: the spread test
    // of the blocks' largest excursions alone (5 %) does not pass them.
    let zmax = |b: usize| (8 + 256 * b..8 + 256 * (b + 1)).map(|n| noisy(0.0)(n)[idx::Z].abs()).fold(0.0, f64::max);
    let m = [zmax(0), zmax(1), zmax(2)];
    let (lo, hi) = (m.iter().copied().fold(f64::INFINITY, f64::min), m.iter().copied().fold(0.0, f64::max));
    assert!(lo < 0.95 * hi, "{m:?}");
    // Their sub-blocks show no drift: stationary after three blocks.
    assert_eq!(watch(&opts, 10_000, noisy(0.0)), ("irregular", 8 + 3 * 256));
    // Growing by 0.025 % per section (13 % per two blocks) under the same fluctuations: never
    // stationary over ten more blocks.
    assert_eq!(watch(&opts, 8 + 13 * 256, noisy(2.5e-4)), ("running", 8 + 13 * 256));
    // Decaying as fast: the same.
    assert_eq!(watch(&opts, 8 + 13 * 256, noisy(-2.5e-4)), ("running", 8 + 13 * 256));
}

#[test]
fn a_block_on_a_known_irregular_attractor_stops_the_run_and_nothing_else_does() {
    let opts = SteadyOptions { watch_x: false, irregular_block: 32, ..SteadyOptions::default() };
    // The torus's fingerprint, from a run that ended stationary: the mean of its three blocks.
    let (w, _) = watcher(&opts, 1000, torus(1.0));
    let fp = w.fingerprint.expect("a stationary run has a fingerprint");
    assert!(!w.matched_known);
    // Its largest excursion of z: (1 + 0.2) in units of the size, to within the torus's sampling.
    assert!((fp.peaks[idx::Z] - 1.2).abs() < 1e-3, "{fp:?}");
    assert!(fp.residual > STATIONARY_MIN_RESIDUAL);
    let knows = |k: Fingerprint| SteadyOptions { known_irregular: [None, Some(k)], ..opts };
    // Another run on the same attractor (a later stretch of the torus) stops after one block.
    let later = |n: usize| torus(1.0)(n + 5000);
    let (w, n) = watcher(&knows(fp), 1000, later);
    assert_eq!((w.irregular, w.matched_known, n), (true, true, 8 + 32));
    // An attractor 10 % larger in every component: three blocks of its own, as without it.
    assert_eq!(watch(&knows(fp), 1000, |n| torus(1.1)(n + 5000)), ("irregular", 8 + 3 * 32));
    // Nor does a fingerprint 10 % off in phi alone match (its statistics alone: without cells).
    let mut phi_off = Fingerprint { cells: Cells::EMPTY, ..fp };
    phi_off.peaks[idx::PHI] *= 1.1;
    let (w, n) = watcher(&knows(phi_off), 1000, later);
    assert_eq!((w.irregular, w.matched_known, n), (true, false, 8 + 3 * 32));
    // Nor does the jitter of a converged cycle match a fingerprint with its own statistics: it is
    // below the residual floor.
    let tight = SteadyOptions {
        periodic_tol: 1e-15,
        ..knows(Fingerprint { residual: 2e-5, peaks: [1.3; 6], cells: Cells::EMPTY })
    };
    let jitter = |n: usize| two(0.0)(n) + 1e-5 * torus(1.0)(n);
    assert_eq!(watch(&tight, 3000, jitter), ("running", 3000));
    // Without stationarity blocks a fingerprint does nothing.
    let off = SteadyOptions { irregular_block: 0, ..knows(fp) };
    assert_eq!(watch(&off, 1000, later).0, "running");
}

#[test]
fn cells_mark_the_visited_states_and_their_neighbours_only() {
    // Points on a circle in (z, phi) at phid = 1: the grid spans the box widened by one cell.
    let pts: Vec<[f64; 3]> = (0..500)
        .map(|n| {
            let a = std::f64::consts::TAU * n as f64 / 500.0;
            [a.cos(), a.sin(), 1.0 + 0.1 * (3.0 * a).sin()]
        })
        .collect();
    let g = Cells::from_points(&pts);
    assert!(!g.is_empty());
    let w = 2.0 / (CELLS - 2) as f64;
    assert!((g.lo[0] - (-1.0 - w)).abs() < 1e-12 && (g.hi[0] - (1.0 + w)).abs() < 1e-12, "{:?} {:?}", g.lo, g.hi);
    let at = |z: f64, phi: f64, phid: f64| g.contains(&State::new(z, 0.0, 0.0, 0.0, phi, phid));
    // Every point it was built from, and a point within half a cell of one.
    for p in &pts {
        assert!(at(p[0], p[1], p[2]));
    }
    assert!(at(0.5f64.sqrt() + 0.4 * w, 0.5f64.sqrt(), 1.0 + 0.1 * (3.0 * std::f64::consts::FRAC_PI_4).sin()));
    // Not the circle's centre (the attractor's hole), nor a circle 20 % larger, nor outside the grid.
    assert!(!at(0.0, 0.0, 1.0));
    assert!(!at(1.2 * 0.5f64.sqrt(), 1.2 * 0.5f64.sqrt(), 1.0 + 0.1 * (3.0 * std::f64::consts::FRAC_PI_4).sin()));
    assert!(!at(3.0, 0.0, 1.0) && !at(f64::NAN, 0.0, 1.0));
    // No grid from nothing, from NaN, or from a component that does not move.
    assert!(Cells::from_points(&[]).is_empty());
    assert!(Cells::from_points(&[[0.0, 1.0, f64::NAN], [1.0, 0.0, 2.0]]).is_empty());
    assert!(Cells::from_points(&[[0.0, 1.0, 2.0], [1.0, 0.0, 2.0]]).is_empty());
    assert!(!Cells::EMPTY.contains(&State::zeros()));
}

#[test]
fn sections_in_a_known_attractors_cells_stop_the_run_after_a_short_run_of_them() {
    let opts = SteadyOptions { watch_x: false, irregular_block: 128, ..SteadyOptions::default() };
    let (w, n) = watcher(&opts, 2000, torus(1.0));
    assert_eq!((w.irregular, n), (true, 8 + 3 * 128));
    let fp = w.fingerprint.expect("a stationary run has a fingerprint");
    assert!(!fp.cells.is_empty());
    // Block statistics that cannot match (excursions 50 % off): only the cells can.
    let cells_only = |cells: Cells| Fingerprint { peaks: fp.peaks.map(|p| 1.5 * p), cells, ..fp };
    let knows = |k: Fingerprint| SteadyOptions { known_irregular: [None, Some(k)], ..opts };
    // A later stretch of the torus stops once RECUR_SECTIONS sections in a row (counted from the
    // 9th, the first with a residual) fell in the cells, before a block of 128 is complete. (The
    // torus is a surface in the section: its 384 states leave gaps in its cells that a later
    // section may fall into, which starts the count again.)
    let later = |n: usize| torus(1.0)(n + 5000);
    let (w, n) = watcher(&knows(cells_only(fp.cells)), 2000, later);
    assert_eq!((w.irregular, w.matched_known), (true, true));
    assert!((8 + RECUR_SECTIONS..8 + 128).contains(&n), "{n}");
    // It reports the attractor it matched, without cells of its own.
    let got = w.fingerprint.expect("matched");
    assert_eq!((got.residual, got.cells.is_empty()), (fp.residual, true));
    // An attractor 10 % larger in every component: its own three blocks.
    let (w, n) = watcher(&knows(cells_only(fp.cells)), 2000, |n| torus(1.1)(n + 5000));
    assert_eq!((w.irregular, w.matched_known, n), (true, false, 8 + 3 * 128));
    // A cycle approached through the attractor's cells (its section states are in them, its
    // repetition residual shrinks far below the attractor's): recognised as periodic, not matched.
    let path: Vec<[f64; 3]> = (0..400).map(|n| Cells::point(&two(0.9)(n))).collect();
    assert_eq!(watch(&knows(cells_only(Cells::from_points(&path))), 2000, two(0.9)).0, "periodic");
    // A converged cycle's jitter in cells of its own, with its own residual: below the floor.
    let tight = SteadyOptions { periodic_tol: 1e-15, ..opts };
    let jitter = |n: usize| two(0.0)(n) + 1e-5 * torus(1.0)(n);
    let own: Vec<[f64; 3]> = (0..400).map(|n| Cells::point(&jitter(n))).collect();
    let k = Fingerprint { residual: 2e-5, peaks: [1.3; 6], cells: Cells::from_points(&own) };
    assert!(!k.cells.is_empty());
    let tight_knows = SteadyOptions { known_irregular: [Some(k), None], ..tight };
    assert_eq!(watch(&tight_knows, 3000, jitter), ("running", 3000));
}

#[test]
fn an_escape_in_free_flight_inside_the_disk_is_a_missed_event() {
    // The state a missed contact event leaves: the pin in free flight 1 mm inside the disk, its law
    // force far positive. An escape in contact, or off the disk, stays an escape.
    let s = Slider::new(Params { contact: crate::model::ContactModel::Unilateral, ..Params::seed() }).unwrap();
    let lim = s.p.escape_limit;
    let inside = State::new(-lim, -0.09, 0.0, 0.0, 0.0, 0.0);
    let above = State::new(lim, 0.09, 0.0, 0.0, 0.0, 0.0);
    let by = crate::ode::Outcome::StoppedByEvent;
    assert_eq!(end_status(&s, by, &inside, ContactMode::Free), Status::EventMissed);
    assert_eq!(end_status(&s, by, &inside, ContactMode::Contact), Status::Diverged);
    assert_eq!(end_status(&s, by, &above, ContactMode::Free), Status::Diverged);
    // Not at the limit: whatever the outcome says.
    let near = State::new(-0.5 * lim, -0.09, 0.0, 0.0, 0.0, 0.0);
    assert_eq!(end_status(&s, crate::ode::Outcome::Finished, &near, ContactMode::Free), Status::Success);
    let opts = options_for(&s, &Tolerances::new(1e-8));
    let f = run_failure(Status::EventMissed, &s, 2.07, &inside, 1e-4, 100, 30.0, &opts).unwrap();
    assert_eq!(f.status(), Status::EventMissed);
    let text = f.to_string();
    assert!(text.contains("free flight inside the disk") && text.contains("a contact event was missed"), "{text}");
}

#[test]
fn an_unsettled_run_reports_its_closest_repetition() {
    let opts = SteadyOptions { watch_x: false, ..SteadyOptions::default() };
    // One section: nothing to compare with.
    assert_eq!(watcher(&opts, 1, two(0.99)).0.nearest(), None);
    // Converging on a period-2 cycle at 0.99 per section, not yet repeated to 1e-5 after 200 and
    // 300 sections: the closest repetition is after 2 sections (those after 4, 6, 8 reduce to
    // it), over two section intervals, and its residual shrinks as 0.99^100 = 0.37 in between.
    let (w200, n200) = watcher(&opts, 200, two(0.99));
    let (w300, n300) = watcher(&opts, 300, two(0.99));
    assert_eq!((n200, n300), (200, 300), "not settled");
    let (a, b) = (w200.nearest().expect("sections"), w300.nearest().expect("sections"));
    assert_eq!((a.multiplicity, b.multiplicity), (2, 2));
    assert!((b.period - 0.02).abs() < 1e-12, "{}", b.period);
    assert_eq!(b.y, two(0.99)(299));
    let ratio = b.residual / a.residual;
    assert!((0.2..0.6).contains(&ratio), "{} -> {}: {ratio}", a.residual, b.residual);
    assert!(b.residual > opts.periodic_tol && b.residual < 1e-2, "{}", b.residual);
    // Quasi-periodic motion repeats nowhere near as well: at best to 9 % (a near return of the
    // golden-ratio phase after 8 sections), far above the 1e-2 from which a sweep shoots.
    let far = watcher(&opts, 300, torus(1.0)).0.nearest().expect("sections").residual;
    assert!(far > 0.05, "{far}");
}

/// Section states converging on a period-1 cycle along a slow mode whose multiplier is complex,
/// `rho e^(i theta)` per section: the deviation turns about the cycle, so the repetition residual
/// on the section swings while its envelope shrinks by `rho` per section.
fn spiral(rho: f64, theta: f64, amp: f64) -> impl Fn(usize) -> State {
    let sizes = characteristic_sizes(&Slider::seed());
    move |n: usize| {
        let (c, s) = ((theta * n as f64).cos(), (theta * n as f64).sin());
        let dev = amp * rho.powi(n as i32);
        State::from_fn(|k, _| sizes[k] * (1.0 + dev * if k % 2 == 0 { c } else { s }))
    }
}

#[test]
fn a_slow_approach_stops_on_its_shrinking_envelope_and_nothing_else_does() {
    // A periodic_tol nothing reaches: only the approach test can stop the runs.
    // The watcher alone: its check (shooting, above this module) is never called here, but the test
    // is on only with one.
    let check: ApproachCheck = |_, _, _, _, _| (ApproachVerdict::Nothing, Stats::default());
    let opts = SteadyOptions {
        watch_x: false,
        periodic_tol: 1e-14,
        approach_periods: 16,
        approach_check: Some(check),
        ..SteadyOptions::default()
    };
    // A slow mode (0.99 a section) turning by 1 rad a section: the residual swings, the envelope shrinks.
    let (w, n) = watcher(&opts, 5000, spiral(0.99, 1.0, 0.3));
    assert!(w.approach && w.found.map(|f| f.0) == Some(1), "{:?} after {n}", w.found);
    // It stops once three blocks of 16 sections shrank in a row and the newest is at most 1e-3:
    // the residual is about the deviation times |1 - e^(-i)| / 0.99 = 0.96 at most, which falls
    // from 0.3 to 1e-3 after some 560 sections (468 here: the compared components' largest
    // swing is a little less), and not before 0.99^n 0.3 < 1e-3, 300 sections.
    assert!((300..700).contains(&n), "{n}");
    assert!(w.nearest().is_some_and(|r| r.residual <= APPROACH_TOL));
    // Without a check the test is off.
    let none = SteadyOptions { approach_check: None, ..opts };
    assert_eq!(watch(&none, 2000, spiral(0.99, 1.0, 0.3)).0, "running");
    // Off (0), or on a torus whose residual never shrinks, or growing by 1 % a section (17 % a
    // block, more than the block's largest sample can miss the swing by: 1 - cos(1/2) = 12 %,
    // which a slower growth may alias into a shrinking block; shooting then finds no stable orbit
    // and the run goes on), from 1e-6 so that it stays below 1e-3 for some 690 sections: no stop.
    let off = SteadyOptions { approach_periods: 0, ..opts };
    assert_eq!(watch(&off, 2000, spiral(0.99, 1.0, 0.3)).0, "running");
    assert_eq!(watch(&opts, 2000, torus(1.0)).0, "running");
    let (w, n) = watcher(&opts, 690, spiral(1.01, 1.0, 1e-6));
    assert!(w.found.is_none() && !w.decayed && !w.irregular, "{:?} {} {} after {n}", w.found, w.approach, w.decayed);
}

#[test]
fn a_run_is_intermittent_once_it_came_back_to_one_unstable_cycle_three_times_after_leaving_it() {
    use super::observer::Saddle;
    let (period, a1, mu) = (0.0205, 2.8e-6, 1.04);
    let mut sd = None;
    // The first visit, and the same cycle again before the run left it: one visit.
    assert_eq!(Saddle::visit(&mut sd, period, a1, mu, 2, 6), None);
    sd.as_mut().unwrap().watch(0.5 * DEPART_TOL);
    assert_eq!(Saddle::visit(&mut sd, period * (1.0 + 1e-6), a1, mu, 2, 6), None);
    assert_eq!(sd.unwrap().cycle.visits, 1);
    // A burst beyond DEPART_TOL, then the same cycle (period and A1 within SAME_SADDLE): the second.
    sd.as_mut().unwrap().watch(2.0 * DEPART_TOL);
    assert_eq!(Saddle::visit(&mut sd, period, a1 * (1.0 - 0.5 * SAME_SADDLE), mu, 2, 6), None);
    assert_eq!(sd.unwrap().cycle.visits, 2);
    // Another cycle (A1 off by twice SAME_SADDLE) starts the count again, and so does a period off by as much.
    let mut other = sd;
    other.as_mut().unwrap().watch(1.0);
    assert_eq!(Saddle::visit(&mut other, period, a1 * (1.0 + 2.0 * SAME_SADDLE), mu, 2, 6), None);
    assert_eq!(other.unwrap().cycle.visits, 1);
    let mut other = sd;
    other.as_mut().unwrap().watch(1.0);
    assert_eq!(Saddle::visit(&mut other, period * (1.0 + 2.0 * SAME_SADDLE), a1, mu, 2, 6), None);
    assert_eq!(other.unwrap().cycle.visits, 1);
    // Left again and back: the third visit is intermittent motion, reported with the cycle.
    sd.as_mut().unwrap().watch(2.0 * DEPART_TOL);
    let im = Saddle::visit(&mut sd, period, a1, 1.05, 2, 6).expect("third visit");
    assert_eq!(im, Intermittent { period, largest: mu, visits: INTERMITTENT_VISITS, kind: 2 });
}

#[test]
fn a_motion_of_the_frictional_mode_alone_is_not_taken_for_rest() {
    // Under speed-dependent friction x is compared. Without a moment arm friction puts no torque on
    // phi, so a disturbance of x' alone leaves z at exactly 0 (no section is ever crossed), and the
    // rest shortcut on z alone (|z| below a millionth of the decay amplitude) called the motion
    // decayed at the first step, with x' at a tenth of its size. It rings down at the friction
    // mode's own rate until every compared component is below the decay amplitude (1e-3 of its
    // size): from 0.1, ln(100) / rate.
    let p = Params { friction_law: FrictionLaw::Switch, mu_static: 0.3, moment_arm: 0.0, ..Params::seed() };
    let s = Slider::new(p).unwrap();
    let sizes = characteristic_sizes(&s);
    let y0 = State::new(0.0, 0.0, 0.0, 0.1 * sizes[idx::XD], 0.0, 0.0);
    let r = run_to_steady(&s, &y0, &SteadyOptions { t_max: 60.0, ..SteadyOptions::default() });
    let rate = -crate::linear::linear_stability(&s).mode(crate::linear::ModeKind::Friction).growth_rate;
    let expected = 100f64.ln() / rate;
    let largest = (0..6).map(|k| r.y_end[k].abs() / sizes[k]).fold(0.0, f64::max);
    println!(
        "{:?} at {:.3} s ({expected:.3} s at {rate:.3} 1/s); largest component {largest:.2e} of its size: {:?}",
        r.outcome,
        r.t_end,
        (0..6).map(|k| r.y_end[k] / sizes[k]).collect::<Vec<_>>()
    );
    assert_eq!(r.outcome, SteadyOutcome::Decayed);
    assert_eq!(r.y_end[idx::Z], 0.0);
    assert!(
        rate > 0.0 && (r.t_end / expected - 1.0).abs() < 0.2,
        "decayed at {} s, the mode needs {expected} s",
        r.t_end
    );
    assert!(largest < 1e-3, "at the stop a component is still {largest:e} of its size");
}
