use super::*;

/// `sample_lanes` against the scalar rule lane by lane (`eval_lane` per sample): the same
/// samples bit for bit, the same next times, for both interpolants, with lanes not due, a
/// sample at the step's start and at its end, several samples in one step, and a step cut
/// short (an escape's located crossing: `t1 < t0 + h`).
#[test]
fn samples_on_all_lanes_match_the_scalar_rule() {
    const N: usize = 16;
    let mut x = 0x9e37_79b9_7f4a_7c15u64;
    let mut u = || {
        x = x.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (x >> 11) as f64 / (1u64 << 53) as f64
    };
    for eight in [false, true] {
        let mut d = LaneDense::<6, N>::new();
        d.eight = eight;
        for j in 0..6 {
            for l in 0..N {
                d.y0[j][l] = u() - 0.5;
                for r in 0..7 {
                    d.c[r][j][l] = u() - 0.5;
                }
            }
        }
        let (mut y0, mut y1) = ([[0.0; N]; 6], [[0.0; N]; 6]);
        for j in 0..6 {
            for l in 0..N {
                (y0[j][l], y1[j][l]) = (u(), u());
            }
        }
        let t0: Lw<N> = std::array::from_fn(|_| u());
        let h: Lw<N> = std::array::from_fn(|_| 1e-3 * (0.5 + u()));
        // Lane 3's step ends early, at its located crossing.
        let t1: Lw<N> = std::array::from_fn(|l| if l == 3 { t0[l] + 0.6 * h[l] } else { t0[l] + h[l] });
        // Each lane's sorted times: its start, l % 4 inside the step, its end (lanes 1 mod 5), then beyond.
        let times: Vec<Vec<f64>> = (0..N)
            .map(|l| {
                let mut v = vec![t0[l]];
                let mut inner: Vec<f64> = (0..l % 4).map(|_| t0[l] + (t1[l] - t0[l]) * (0.05 + 0.9 * u())).collect();
                inner.sort_by(f64::total_cmp);
                v.extend(inner);
                if l % 5 == 1 {
                    v.push(t1[l]);
                }
                v.push(t1[l] + 0.5 * h[l]);
                v
            })
            .collect();
        let due: [bool; N] = std::array::from_fn(|l| l % 7 != 2);
        let mut next: Lw<N> = std::array::from_fn(|l| times[l][0]);
        let mut got: Vec<Vec<[f64; 6]>> = vec![Vec::new(); N];
        sample_lanes(&due, &mut next, (&t0, &t1, &h), &d, &y0, &y1, |l, v| {
            got[l].push(std::array::from_fn(|i| v[i]));
            times[l].get(got[l].len()).copied().unwrap_or(f64::INFINITY)
        });
        for l in 0..N {
            let mut want: Vec<[f64; 6]> = Vec::new();
            if due[l] {
                for &t in times[l].iter().take_while(|&&t| t <= t1[l]) {
                    want.push(if t <= t0[l] {
                        std::array::from_fn(|i| y0[i][l])
                    } else if t == t1[l] {
                        std::array::from_fn(|i| y1[i][l])
                    } else {
                        d.eval_lane(l, (t - t0[l]) / h[l])
                    });
                }
            }
            let bits = |v: &Vec<[f64; 6]>| v.iter().flatten().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&got[l]), bits(&want), "eight {eight}, lane {l}");
            assert_eq!(got[l].len(), if due[l] { 1 + l % 4 + (l % 5 == 1) as usize } else { 0 }, "lane {l}");
            let n_next = if due[l] { got[l].len() } else { 0 };
            assert_eq!(next[l].to_bits(), times[l][n_next].to_bits(), "eight {eight}, lane {l}: next time");
        }
    }
}
