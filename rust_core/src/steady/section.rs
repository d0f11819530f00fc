//! The Poincare section `zd = 0` (falling) and the tests that decide when a run to steady state
//! has settled: repetition (periodic), decay, and stationarity (sustained irregular motion).

use super::{
    characteristic_sizes, decay_amplitude, Cells, Fingerprint, Known, SteadyOptions, KNOWN_MAX, MAX_MULTIPLICITY,
    RECUR_SECTIONS,
};
use crate::model::{idx, FrictionLaw, Slider, State};
use crate::ode::Stats;

#[derive(Clone, Copy)]
pub(super) struct Crossing {
    pub(super) t: f64,
    pub(super) y: State,
    /// Largest |y_c| of each component since the previous crossing.
    pub(super) peaks: State,
}

/// Watches the Poincare section and decides when the run has settled.
pub(crate) struct SectionWatcher {
    ring: Vec<Crossing>,
    /// The decay test's measure of each crossing in `ring` (same slots), computed once at its push.
    decay_ring: Vec<f64>,
    n_seen: usize,
    pub(crate) peak_since: f64,
    pub(crate) peaks_since: State,
    tol: f64,
    /// No periodic state at a crossing before this time (`SteadyOptions::hold`).
    hold: f64,
    /// The decay test: the largest `peaks[c] / decay_scale[c]` over the compared components,
    /// times `decay_unit`, below `decay_amp`.
    decay_scale: [f64; 6],
    decay_unit: f64,
    decay_amp: f64,
    pub(super) window: usize,
    pub(super) found: Option<(usize, f64)>,
    pub(super) decayed: bool,
    matches_in_row: [u32; MAX_MULTIPLICITY + 1],
    sizes: [f64; 6],
    /// The components the repetition and decay tests compare (`SteadyOptions::watch_x`).
    pub(super) comps: &'static [usize],
    /// Factor on the repetition tolerance of `x` and `xd`: [`CHECKED_X_SLACK`] where every stop is
    /// checked by shooting (`SteadyOptions::checked_stops`), else 1. It holds in the stop test and
    /// in the reduction of its multiplicity alike: with `x` held to `REDUCE_TOL` in the reduction
    /// alone, the Stribeck sweep's census found the same fractions but took 613 instead of 588
    /// million right-hand sides (8.5 against 7.6 s: stops left at a multiple of their period).
    pub(super) x_slack: f64,
    /// The stationarity test of sustained irregular motion (`SteadyOptions::irregular_block`).
    stationary: Option<Stationarity>,
    /// Below this mean repetition residual the motion is nearly periodic: the repetition test decides.
    stationary_floor: f64,
    pub(super) irregular: bool,
    /// Irregular: the attractor's fingerprint (see [`Fingerprint`]).
    pub(super) fingerprint: Option<Fingerprint>,
    /// Irregular by matching a known fingerprint.
    pub(super) matched_known: bool,
    /// Periods per block of the slow-approach test (`SteadyOptions::approach_periods`; 0: off,
    /// also where no check is handed in, or after a check found no orbit).
    approach_periods: usize,
    /// Per `p`: the envelope of the repetition residual after `p` sections, block by block.
    envelope: [Envelope; MAX_MULTIPLICITY + 1],
    /// The newest `found` is a slow approach's, to be checked by shooting.
    pub(super) approach: bool,
    /// Irregular: stopped as intermittent motion (set by the observer).
    pub(super) intermittent: Option<super::Intermittent>,
    /// A slow approach's check converged on a stable orbit: the summary of a run on it.
    pub(super) measured: Option<Box<super::Summary>>,
    /// The checks' work.
    pub(super) extra: Stats,
}

/// Largest repetition residual at which a steadily contracting approach stops the run
/// (`SteadyOptions::approach_periods`).
pub const APPROACH_TOL: f64 = 1e-3;

/// The largest repetition residual over blocks of `approach_periods * p` crossings: the current
/// block's so far, and the newest three completed (oldest first). Its envelope, not each
/// crossing's residual, since a slow mode with a complex multiplier (the lightly damped `x`
/// oscillator's) turns its deviation about the cycle, and the residual on the section swings
/// with it while its envelope shrinks.
#[derive(Clone, Copy, Default)]
struct Envelope {
    current: f64,
    count: usize,
    done: [f64; 3],
    n_done: usize,
}

impl Envelope {
    /// Add a crossing's residual (NaN: not computed, resets); `true` when this completed a block
    /// and the newest three shrink, each below the one before, the newest at most [`APPROACH_TOL`].
    fn add(&mut self, r: f64, block: usize) -> bool {
        if r.is_nan() {
            *self = Envelope::default();
            return false;
        }
        self.current = self.current.max(r);
        self.count += 1;
        if self.count < block {
            return false;
        }
        self.done = [self.done[1], self.done[2], self.current];
        (self.current, self.count, self.n_done) = (0.0, 0, self.n_done + 1);
        let [a, b, c] = self.done;
        self.n_done >= 3 && c < b && b < a && c <= APPROACH_TOL
    }
}

/// Largest relative spread of three consecutive blocks' mean repetition residuals for stationary motion.
pub const STATIONARY_RESIDUAL_TOL: f64 = 0.25;
/// Largest relative spread of three consecutive blocks' largest excursions (each compared
/// component), or of the drift of their sub-blocks' largest excursions over two blocks fitted by
/// least squares: a decay or a growth, however slow, shows there first.
pub const STATIONARY_PEAK_TOL: f64 = 0.05;
/// Sub-blocks per block: besides its largest excursion, a block records each component's largest
/// excursion in each of its sub-blocks, for the trend test of [`STATIONARY_PEAK_TOL`].
pub const STATIONARY_SUBBLOCKS: usize = 8;
/// The residual floor of the stationarity test in units of `periodic_tol`, and never below
/// [`STATIONARY_MIN_RESIDUAL`].
pub const STATIONARY_FLOOR: f64 = 100.0;
/// The smallest residual floor (in characteristic sizes): a cycle repeats far better than this
/// even where `periodic_tol` asks for more than the integration can give (a cycle's residual is
/// then rounding and integration error, steady from block to block, and must not pass for
/// irregular motion).
pub const STATIONARY_MIN_RESIDUAL: f64 = 1e-3;

/// One block of sections: the mean repetition residual and the largest excursion of each
/// component, both in units of the characteristic sizes, and the largest excursions of each
/// sub-block.
#[derive(Clone, Copy, Default)]
struct Block {
    residual: f64,
    peaks: [f64; 6],
    sub: [[f64; 6]; STATIONARY_SUBBLOCKS],
}

/// Block statistics of the section states, for the stationarity test.
///
/// The repetition residual of a section state is its distance to the nearest of the `p = 1..=8`
/// states before it (the largest component difference in units of the characteristic sizes).
/// Converging on a cycle of any multiplicity drives it to zero geometrically; on sustained
/// irregular motion it stays of the order of the attractor's spread. The motion is stationary
/// when, over the newest three blocks, the mean residual is above the floor and spread by less
/// than `STATIONARY_RESIDUAL_TOL`, and each component's largest excursion by less than
/// `STATIONARY_PEAK_TOL` (a decay or a growth, however slow, shows there first) or, where
/// chaotic motion spreads a block's largest excursion by more (it is an extreme of a fluctuating
/// quantity), the drift over two blocks of a least-squares line through the largest excursions of
/// the three blocks' [`STATIONARY_SUBBLOCKS`] sub-blocks each is below `STATIONARY_PEAK_TOL`. A
/// drift hidden by the fluctuations passes: the fluctuations bound what the test can see.
///
/// What it may take for irregular motion: an approach to a cycle whose residual shrinks by less
/// than 25 % per two blocks (multiplier above 0.9994 per section for the default blocks of 256
/// sections: thousands of sections to converge, more than a census's `t_max` at these frequencies), an
/// amplitude drifting by less than 5 % per two blocks, or transient chaos that leaves later.
struct Stationarity {
    block: usize,
    n: usize,
    sum: f64,
    /// The largest excursions of each sub-block of the block being filled (the block's own are
    /// their maxima).
    sub: [[f64; 6]; STATIONARY_SUBBLOCKS],
    done: [Block; 3],
    n_done: usize,
    /// Fingerprints of known attractors (`SteadyOptions::known_irregular`).
    known: Known,
    /// The newest `3 block` section states' cell coordinates (a ring; `n_cloud` pushed so far):
    /// the cells of a stationary run.
    cloud: Vec<[f64; 3]>,
    n_cloud: usize,
    /// Per known attractor: sections in a row in its cells.
    hits: [usize; KNOWN_MAX],
    /// The newest [`RECUR_SECTIONS`] repetition residuals (a ring, at `n_cloud`).
    recent: [f64; RECUR_SECTIONS],
}

/// Whether two positive statistics agree within `tol` (the smaller at least `1 - tol` of the larger).
fn close(a: f64, b: f64, tol: f64) -> bool {
    a.min(b) >= (1.0 - tol) * a.max(b)
}

impl Stationarity {
    /// Add one section's residual and excursions; `true` when this completed a block.
    fn add(&mut self, residual: f64, peaks: [f64; 6]) -> bool {
        let g = self.subblocks();
        let sub = &mut self.sub[self.n * g / self.block];
        self.n += 1;
        self.sum += residual;
        for (s, p) in sub.iter_mut().zip(peaks) {
            *s = s.max(p);
        }
        if self.n < self.block {
            return false;
        }
        let peaks = std::array::from_fn(|c| self.sub[..g].iter().fold(0.0, |m: f64, s| m.max(s[c])));
        self.done[self.n_done % 3] = Block { residual: self.sum / self.n as f64, peaks, sub: self.sub };
        self.n_done += 1;
        (self.n, self.sum, self.sub) = (0, 0.0, [[0.0; 6]; STATIONARY_SUBBLOCKS]);
        true
    }

    /// Whether the newest three blocks are stationary (see the type's documentation).
    fn stationary(&self, floor: f64, comps: &[usize]) -> bool {
        if self.n_done < 3 {
            return false;
        }
        let spread_ok = |v: [f64; 3], tol: f64| {
            let (lo, hi) = (v.iter().copied().fold(f64::INFINITY, f64::min), v.iter().copied().fold(0.0, f64::max));
            close(lo, hi, tol)
        };
        let r = self.done.map(|b| b.residual);
        let peaks_ok = |c: usize| {
            spread_ok(self.done.map(|b| b.peaks[c]), STATIONARY_PEAK_TOL) || self.drift(c).abs() <= STATIONARY_PEAK_TOL
        };
        r.iter().all(|&x| x >= floor) && spread_ok(r, STATIONARY_RESIDUAL_TOL) && comps.iter().all(|&c| peaks_ok(c))
    }

    /// Sub-blocks of a block ([`STATIONARY_SUBBLOCKS`], fewer only for blocks of fewer sections).
    fn subblocks(&self) -> usize {
        STATIONARY_SUBBLOCKS.min(self.block)
    }

    /// The drift of component `c` over two blocks relative to its mean: the least-squares line
    /// through the newest three blocks' sub-block excursions, in time order. Chaotic motion
    /// spreads the blocks' largest excursions by more than [`STATIONARY_PEAK_TOL`] (a block's
    /// largest is an extreme of a fluctuating quantity), while its fitted drift stays small; a
    /// steady decay or growth moves both.
    fn drift(&self, c: usize) -> f64 {
        let g = self.subblocks();
        let ys = (0..3).flat_map(|i| self.done[(self.n_done + i) % 3].sub[..g].iter().map(move |s| s[c]));
        let n = (3 * g) as f64;
        let (xm, ym) = ((n - 1.0) / 2.0, ys.clone().sum::<f64>() / n);
        let (mut sxy, mut sxx) = (0.0, 0.0);
        for (x, y) in ys.enumerate() {
            let dx = x as f64 - xm;
            (sxy, sxx) = (sxy + dx * (y - ym), sxx + dx * dx);
        }
        if ym > 0.0 {
            sxy / sxx * (2 * g) as f64 / ym
        } else {
            0.0
        }
    }

    /// The mean of the newest three blocks (the fingerprint of a stationary run).
    fn mean(&self) -> Fingerprint {
        let third = |f: &dyn Fn(&Block) -> f64| self.done.iter().map(f).sum::<f64>() / 3.0;
        Fingerprint {
            residual: third(&|b| b.residual),
            peaks: std::array::from_fn(|c| third(&|b| b.peaks[c])),
            cells: Cells::from_points(&self.cloud),
        }
    }

    /// The newest block as a fingerprint.
    fn newest(&self) -> Fingerprint {
        let b = self.done[(self.n_done + 2) % 3];
        Fingerprint { residual: b.residual, peaks: b.peaks, cells: Cells::EMPTY }
    }

    /// Record a section state's cell coordinates in the ring of the newest three blocks.
    fn record(&mut self, p: [f64; 3]) {
        let cap = 3 * self.block;
        if self.cloud.len() < cap {
            self.cloud.push(p);
        } else {
            self.cloud[self.n_cloud % cap] = p;
        }
        self.n_cloud += 1;
    }

    /// The known attractor (slot) the run is on by recurrence: the section state `y`, with its
    /// repetition `residual`, ends [`RECUR_SECTIONS`] sections in a row in that attractor's cells
    /// whose mean residual is above `floor` and at least half the attractor's (a cycle's approach
    /// through the attractor's cells does not match).
    fn recurs(&mut self, y: &State, residual: f64, floor: f64) -> Option<usize> {
        self.recent[self.n_cloud % RECUR_SECTIONS] = residual;
        let mut mean = f64::NAN;
        for (j, k) in self.known.iter().enumerate() {
            let Some(k) = k else { continue };
            if !k.cells.contains(y) {
                self.hits[j] = 0;
                continue;
            }
            self.hits[j] += 1;
            if self.hits[j] >= RECUR_SECTIONS {
                if mean.is_nan() {
                    mean = self.recent.iter().sum::<f64>() / RECUR_SECTIONS as f64;
                }
                if mean >= floor && mean >= (1.0 - 2.0 * STATIONARY_RESIDUAL_TOL) * k.residual {
                    return Some(j);
                }
            }
        }
        None
    }

    /// Whether the newest block matches a known fingerprint: within the stationarity tolerances,
    /// and above the residual floor (a cycle's approach never matches). One block suffices: the
    /// known attractor has already passed the three-block test on another run.
    fn matched(&self, floor: f64, comps: &[usize]) -> bool {
        let b = self.newest();
        b.residual >= floor
            && self.known.iter().flatten().any(|k| {
                close(b.residual, k.residual, STATIONARY_RESIDUAL_TOL)
                    && comps.iter().all(|&c| close(b.peaks[c], k.peaks[c], STATIONARY_PEAK_TOL))
            })
    }
}

pub(super) const ALL: [usize; 6] = [0, 1, 2, 3, 4, 5];
pub(super) const NOT_X: [usize; 4] = [idx::Z, idx::ZD, idx::PHI, idx::PHID];

const RING: usize = 64;

/// Where every periodic stop is checked by shooting (`SteadyOptions::checked_stops`), `x` and `xd`
/// repeat to this many times the tolerance of `(z, zd, phi, phid)`: near enough for Newton, and
/// not held back by the friction mode's ring-down. On the switch-law Stribeck sweep's census
/// (K = 32), against 1 (`x` held to the same tolerance): right-hand sides 664 -> 589 million, the
/// census 8.1-8.5 -> 7.6 s; of about 3,100 first stops 170 failed their check instead of 103
/// (each then goes on to a strict stop). Leaving `x` out entirely (0 weight): 572 million, the
/// same time, but 249 failed checks, and at 150 N, 5 cm, 0.8 m/s no gain at all (4 of 26 stops
/// went on).
pub const CHECKED_X_SLACK: f64 = 10.0;

/// Relative repetition tolerance under which a found multiplicity `p` is reduced to a divisor
/// (a period-doubled orbit whose two halves differ by less than this is reported as period-1).
pub const REDUCE_TOL: f64 = 1e-2;

impl SectionWatcher {
    pub(super) fn new(opts: &SteadyOptions, s: &Slider) -> Self {
        let sizes = characteristic_sizes(s);
        SectionWatcher {
            ring: Vec::with_capacity(RING),
            decay_ring: Vec::with_capacity(RING),
            n_seen: 0,
            peak_since: 0.0,
            peaks_since: State::zeros(),
            tol: opts.periodic_tol,
            hold: opts.hold,
            decay_scale: opts.decay_thresholds.unwrap_or(sizes),
            decay_unit: if opts.decay_thresholds.is_some() { 1.0 } else { sizes[0] },
            decay_amp: if opts.decay_thresholds.is_some() { 1.0 } else { decay_amplitude(opts, s) },
            window: opts.decay_window.max(2),
            found: None,
            decayed: false,
            matches_in_row: [0; MAX_MULTIPLICITY + 1],
            sizes,
            comps: if opts.watch_x || s.p.friction_law != FrictionLaw::Constant { &ALL } else { &NOT_X },
            x_slack: if opts.checked_stops { CHECKED_X_SLACK } else { 1.0 },
            stationary: (opts.irregular_block > 0).then(|| Stationarity {
                block: opts.irregular_block,
                n: 0,
                sum: 0.0,
                sub: [[0.0; 6]; STATIONARY_SUBBLOCKS],
                done: [Block::default(); 3],
                n_done: 0,
                known: opts.known_irregular,
                cloud: Vec::with_capacity(3 * opts.irregular_block),
                n_cloud: 0,
                hits: [0; KNOWN_MAX],
                recent: [0.0; RECUR_SECTIONS],
            }),
            stationary_floor: (STATIONARY_FLOOR * opts.stationary_tol.unwrap_or(opts.periodic_tol))
                .max(STATIONARY_MIN_RESIDUAL),
            irregular: false,
            fingerprint: None,
            matched_known: false,
            approach_periods: if opts.approach_check.is_some() { opts.approach_periods } else { 0 },
            envelope: [Envelope::default(); MAX_MULTIPLICITY + 1],
            approach: false,
            measured: None,
            intermittent: None,
            extra: Stats::default(),
        }
    }

    /// The ring slot of the crossing `back` crossings before the newest (0: the newest).
    fn slot(&self, back: usize) -> usize {
        (self.n_seen - 1 - back) % RING
    }

    /// Whether every compared component of `y` other than `z` is below the decay test's threshold
    /// (each in its decay scale, as [`Self::push`] measures a crossing; a displacement and its rate
    /// both, so an oscillation passing through zero does not pass): with `z` at rest no section is
    /// crossed and the decay test never runs, so the rest shortcut on `z`
    /// ([`super::observer::SteadyObserver`]'s `decay_floor`) asks this of the others. On `z` alone
    /// it called a motion of the frictional mode decayed at once where that mode carries almost no
    /// `z`. (A millionth of the threshold, as on `z`, is out of reach: below the integration's
    /// absolute tolerance a component no longer decays reliably.)
    pub(super) fn quiet_beside_z(&self, y: &State) -> bool {
        self.comps
            .iter()
            .filter(|&&k| k != idx::Z)
            .all(|&k| y[k].abs() / self.decay_scale[k] * self.decay_unit < self.decay_amp)
    }

    pub(super) fn get(&self, back: usize) -> &Crossing {
        &self.ring[self.slot(back)]
    }

    pub(super) fn push(&mut self, c: Crossing) {
        // The decay measure: the largest compared component in units of its decay scale.
        let d = self.comps.iter().map(|&k| c.peaks[k] / self.decay_scale[k]).fold(0.0, f64::max);
        if self.ring.len() < RING {
            self.ring.push(c);
            self.decay_ring.push(d);
        } else {
            self.ring[self.n_seen % RING] = c;
            self.decay_ring[self.n_seen % RING] = d;
        }
        self.n_seen += 1;
        self.check();
    }

    /// The relative repetition residual of the newest section state against the one `d` crossings
    /// back: the largest compared component's difference in units of what [`Self::repeats`]
    /// allows per unit of `rel`.
    pub(super) fn residual(&self, d: usize) -> f64 {
        self.residual_over(d, self.comps)
    }

    /// [`Self::residual`] over the components `comps`.
    fn residual_over(&self, d: usize, comps: &[usize]) -> f64 {
        self.residual_within(d, comps, &self.span_amp(d))
    }

    /// [`Self::residual_over`] with the span's amplitude `amp` given (as [`Self::repeats_within`]).
    fn residual_within(&self, d: usize, comps: &[usize], amp: &State) -> f64 {
        let (a, b) = (self.get(0), self.get(d));
        comps.iter().map(|&c| (a.y[c] - b.y[c]).abs() / amp[c].max(1e-6 * self.sizes[c])).fold(0.0, f64::max)
    }

    /// The newest section state's closest repetition ([`super::Nearest`]; `None` before two
    /// sections).
    pub(super) fn nearest(&self) -> Option<super::Nearest> {
        let top = MAX_MULTIPLICITY.min(self.n_seen.saturating_sub(1));
        let (p, residual) =
            (1..=top).map(|p| (p, self.residual(p))).fold(None, |best: Option<(usize, f64)>, (p, r)| match best {
                Some((_, rb)) if rb <= r => best,
                _ => Some((p, r)),
            })?;
        let d = self.reduced(p);
        let a = self.get(0);
        Some(super::Nearest { y: a.y, period: a.t - self.get(d).t, multiplicity: d as u32, residual })
    }

    /// `p` reduced to its smallest divisor whose section states repeat to [`REDUCE_TOL`] (or
    /// `periodic_tol` where that is looser), `p` itself where none does.
    fn reduced(&self, p: usize) -> usize {
        (1..p).filter(|&d| p.is_multiple_of(d)).find(|&d| self.repeats(d, REDUCE_TOL.max(self.tol))).unwrap_or(p)
    }

    /// Whether the newest section state equals the one `d` crossings back within `rel` relative
    /// to each component's amplitude (floored at a millionth of its characteristic size, so that a
    /// component that hardly moves does not demand the impossible).
    fn repeats(&self, d: usize, rel: f64) -> bool {
        self.repeats_within(d, rel, &self.span_amp(d))
    }

    /// The motion's own scale over the newest `d` crossings: the sup of their peaks (a minor
    /// maximum's interval alone may miss a component's extreme).
    fn span_amp(&self, d: usize) -> State {
        (0..d).fold(State::zeros(), |m, k| m.sup(&self.get(k).peaks))
    }

    /// [`Self::repeats`] with the span's amplitude `amp` given (the sup of the newest `d` crossings' peaks).
    fn repeats_within(&self, d: usize, rel: f64, amp: &State) -> bool {
        let (a, b) = (self.get(0), self.get(d));
        let slack = |c: usize| if c == idx::X || c == idx::XD { self.x_slack } else { 1.0 };
        self.comps.iter().all(|&c| (a.y[c] - b.y[c]).abs() <= rel * slack(c) * amp[c].max(1e-6 * self.sizes[c]))
    }

    fn check(&mut self) {
        let n = self.n_seen;
        // The sup of the newest p crossings' peaks, grown with p (the same as `repeats` folds).
        let mut amp = State::zeros();
        for p in 1..=MAX_MULTIPLICITY {
            if n <= p {
                break;
            }
            amp = amp.sup(&self.get(p - 1).peaks);
            let a = self.get(0);
            let b = self.get(p);
            let mut ok = a.t >= self.hold && self.repeats_within(p, self.tol, &amp);
            let dt_now = a.t - b.t;
            if ok && n > 2 * p {
                let dt_prev = self.get(p).t - self.get(2 * p).t;
                ok = (dt_now - dt_prev).abs() <= self.tol.max(1e-12) * dt_now;
            } else if n <= 2 * p {
                ok = false;
            }
            if ok {
                self.matches_in_row[p] += 1;
                if self.matches_in_row[p] >= 2 {
                    // A residual slow transient can fool the test: at the seed's bouncing cycle
                    // the lightly damped x mode (306 rad/s) is nearly commensurate with two cycle
                    // periods, so p = 4 matches while the true p = 2 misses by the residual.
                    // Reduce p to its smallest divisor whose states repeat to REDUCE_TOL; a true
                    // sub-multiple structure (major/minor maxima of z) differs by far more.
                    let d = self.reduced(p);
                    self.found = Some((d, self.get(0).t - self.get(d).t));
                    return;
                }
            } else {
                self.matches_in_row[p] = 0;
            }
        }
        if self.approach_periods > 0 && self.slow_approach() {
            return;
        }
        // Decay: the motion, measured on every component in units of its characteristic size
        // (so that a torsion oscillation with little z is not missed) or of its own threshold,
        // is small over the newest window and below the window before it.
        let w = self.window;
        if n >= 2 * w {
            let rel = |b: usize| self.decay_ring[self.slot(b)];
            let recent = (0..w).map(rel).fold(0.0, f64::max);
            let before = (w..2 * w).map(rel).fold(0.0, f64::max);
            if recent * self.decay_unit < self.decay_amp && recent < before {
                self.decayed = true;
                return;
            }
        }
        if self.stationary.is_none() || n <= MAX_MULTIPLICITY {
            return;
        }
        let a = self.get(0);
        let residual = (1..=MAX_MULTIPLICITY)
            .map(|p| {
                let b = self.get(p);
                self.comps.iter().map(|&c| (a.y[c] - b.y[c]).abs() / self.sizes[c]).fold(0.0, f64::max)
            })
            .fold(f64::INFINITY, f64::min);
        let peaks = std::array::from_fn(|c| a.peaks[c] / self.sizes[c]);
        let y = a.y;
        let (floor, comps) = (self.stationary_floor, self.comps);
        if let Some(st) = self.stationary.as_mut() {
            let rec = st.recurs(&y, residual, floor);
            st.record(Cells::point(&y));
            if let Some(j) = rec {
                let fp = st.known[j].map(|k| Fingerprint { cells: Cells::EMPTY, ..k });
                (self.irregular, self.matched_known, self.fingerprint) = (true, true, fp);
                return;
            }
            if !st.add(residual, peaks) {
                return;
            }
            if st.stationary(floor, comps) {
                (self.irregular, self.fingerprint) = (true, Some(st.mean()));
            } else if st.matched(floor, comps) {
                (self.irregular, self.matched_known, self.fingerprint) = (true, true, Some(st.newest()));
            }
        }
    }

    /// The slow-approach test (`SteadyOptions::approach_periods`), after the repetition test found
    /// nothing at the newest crossing: where for some `p` (the smallest wins) the envelope of the
    /// residual after `p` sections has shrunk over three blocks of `approach_periods` periods
    /// ([`Envelope`]) to at most [`APPROACH_TOL`], outside the hold, and the period agrees with
    /// the one before to [`APPROACH_TOL`], sets `found` (reduced as the repetition test reduces
    /// it) and `approach`.
    fn slow_approach(&mut self) -> bool {
        let n = self.n_seen;
        let t = self.get(0).t;
        // The sup of the newest p crossings' peaks, grown with p (as `check` grows it; `span_amp`
        // per p folded 36 states per section).
        let mut amp = State::zeros();
        for p in 1..=MAX_MULTIPLICITY {
            // In (z, zd, phi, phid): the check that follows shoots on the whole state, and x's
            // light damping would hold the trigger back (see `SteadyOptions::approach_periods`).
            let r = if n > 2 * p {
                amp = amp.sup(&self.get(p - 1).peaks);
                self.residual_within(p, &NOT_X, &amp)
            } else {
                f64::NAN
            };
            if !self.envelope[p].add(r, self.approach_periods * p) || t < self.hold {
                continue;
            }
            let (dt_now, dt_prev) = (t - self.get(p).t, self.get(p).t - self.get(2 * p).t);
            if (dt_now - dt_prev).abs() > APPROACH_TOL * dt_now {
                continue;
            }
            let d = self.reduced(p);
            (self.found, self.approach) = (Some((d, t - self.get(d).t)), true);
            return true;
        }
        false
    }

    /// A slow approach's stop that its check did not confirm: the run goes on, with no cycle
    /// declared before `hold` (an unstable orbit's), or without approach stops from now on.
    pub(super) fn reject_approach(&mut self, hold: Option<f64>) {
        (self.found, self.approach, self.envelope) = (None, false, [Envelope::default(); MAX_MULTIPLICITY + 1]);
        match hold {
            Some(t) => self.hold = self.hold.max(t),
            None => self.approach_periods = 0,
        }
    }

    /// Mean angular frequency of section crossings over the newest `k` intervals.
    pub(super) fn mean_omega(&self, k: usize) -> f64 {
        let k = k.min(self.n_seen.saturating_sub(1)).min(RING - 1);
        if k == 0 {
            return f64::NAN;
        }
        std::f64::consts::TAU * k as f64 / (self.get(0).t - self.get(k).t)
    }
}
