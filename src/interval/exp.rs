//! `exp` in f64 from a table and a short polynomial, with an error bound
//! proven below, for the interval bounds of [`super::Interval::exp`].
//!
//! On exp-heavy scenes the `libm` crate's `exp` was the largest single cost
//! of a render (metaballs with IAA at 256²: 36% of the samples in `perf`,
//! two calls per interval op). Its algorithm divides once per call; this
//! one does not, and its result is within 0.55 ulp of the real value where
//! it applies, inside the 1 ulp that the 2-ulp widening of transcendental
//! bounds assumes of libm. Outside that range it calls libm.
//!
//! # Algorithm and error bound
//! With N = 128, k = round(x·N/ln 2), j = k mod N, e = (k − j)/N and
//! r = x − k·ln2/N (|r| ≤ ln2/256 < 0.00271):
//! exp(x) = 2^e · 2^(j/N) · exp(r).
//! - 2^(j/N) is a double-double `(hi, lo)` from `EXP2_TABLE`, written
//!   from 80-digit decimal arithmetic: relative error below 2^-105.
//! - ln2/N = `LN2_N_HI + LN2_N_LO`, `LN2_N_HI` with 36 significant bits,
//!   so `k·LN2_N_HI` is exact for |k| < 2^17 and `x − k·LN2_N_HI` is exact
//!   (Sterbenz: the two are within a factor 2 of each other, or k = 0).
//!   The error of r is below 2^-61 (the rounding of `k·LN2_N_LO`, about
//!   2^-79, and of the last subtraction, 2^-53·|r|).
//! - p = r + r²(1/2 + r(1/6 + r(1/24 + r/120))) is exp(r) − 1 to within
//!   |r|⁶/720 < 2^-60 plus evaluation rounding below 2^-61.
//! - y = hi + (lo + hi·p): the rounding of `hi·p` and of the inner sum
//!   are below 2^-60 each (|hi·p| < 2^-7.5), the term lo·p left out is
//!   below 2^-60, and the last sum rounds by at most half an ulp of y.
//!   The errors before the last rounding add up to less than 2^-57 in
//!   relative terms, a twentieth of an ulp (y lies in [0.99, 2], where an
//!   ulp is at least 2^-53): |y − 2^(j/N)·exp(r)| ≤ 0.55 ulp(y).
//! - Scaling y by 2^e is exact while the result is a normal number, which
//!   |x| ≤ [`FAST_RANGE`] ensures (exp(±700) lies within 1e-305..1e305).
//!
//! Only `+ − ×` in round-to-nearest are used (no fused multiply-add, no
//! platform libm), so every platform gives the same bits. The tests check
//! the bound against correctly rounded values from 60-digit decimal
//! arithmetic (`tests/data/exp_cases.txt`). `tests/data/exp_cases.py`
//! writes those values, and prints the constants and the table below.

/// |x| up to which the table path applies; libm beyond (overflow,
/// subnormal results, infinities, NaN).
pub const FAST_RANGE: f64 = 700.0;

/// N/ln 2, N = 128.
const INV_LN2_N: f64 = 184.6649652337873;
/// ln 2 / N to 36 significant bits.
const LN2_N_HI: f64 = 0.005415212348111709;
/// ln 2 / N − `LN2_N_HI`.
const LN2_N_LO: f64 = 1.2864023111638346e-14;
/// 1.5·2^52: adding it rounds a number below 2^51 in magnitude to an
/// integer (round half to even), whose low bits are then those of the sum.
const ROUND_SHIFT: f64 = 6755399441055744.0;

/// exp(x) within 0.55 ulp of the real value for |x| ≤ [`FAST_RANGE`]
/// (libm's result elsewhere).
#[inline]
pub fn exp(x: f64) -> f64 {
    if x.is_nan() || x.abs() > FAST_RANGE {
        return libm::exp(x);
    }
    let shifted = x * INV_LN2_N + ROUND_SHIFT;
    let kf = shifted - ROUND_SHIFT;
    // The low 32 bits of the shifted sum are k in two's complement.
    let k = shifted.to_bits() as i32;
    let r = (x - kf * LN2_N_HI) - kf * LN2_N_LO;
    let (hi, lo) = EXP2_TABLE[(k & 127) as usize];
    let p = r + r * r * (0.5 + r * (1.0 / 6.0 + r * (1.0 / 24.0 + r * (1.0 / 120.0))));
    let y = hi + (lo + hi * p);
    let e = k >> 7;
    y * f64::from_bits(((e + 1023) as u64) << 52)
}

/// 2^(j/128) for j = 0..128, each as the nearest f64 and the nearest f64
/// to what remains (80-digit decimal arithmetic). Entry 64 is √2, written
/// as computed like the others.
#[rustfmt::skip]
#[allow(clippy::approx_constant)]
static EXP2_TABLE: [(f64, f64); 128] = [
    (1.0, 0.0),
    (1.0054299011128027, 9.499186535455032e-17),
    (1.0108892860517005, -1.5234778603368577e-17),
    (1.016378314910953, -5.77217007319966e-17),
    (1.0218971486541166, 5.109225028973444e-17),
    (1.0274459491187637, -4.9560741746453704e-17),
    (1.0330248790212284, 7.600838874027088e-18),
    (1.0386341019613787, 5.996273788852511e-17),
    (1.0442737824274138, 8.551889705537965e-17),
    (1.0499440858006872, 5.592937848127003e-17),
    (1.0556451783605572, 1.759325738772092e-18),
    (1.061377227289262, -1.1973537085365658e-17),
    (1.0671404006768237, -7.899853966841582e-17),
    (1.0729348675259756, -3.839668843358824e-18),
    (1.0787607977571199, -6.656660436056593e-17),
    (1.0846183622133092, 3.166152845816346e-17),
    (1.0905077326652577, -3.046782079812471e-17),
    (1.0964290818163769, -5.919933484449316e-17),
    (1.102382583307841, 5.2660368715706944e-17),
    (1.1083684117236787, -8.786813845180527e-17),
    (1.1143867425958924, 1.0410278456845571e-16),
    (1.1204377524096067, -6.201085906554179e-17),
    (1.1265216186082418, 5.165856758795457e-17),
    (1.1326385195987192, 3.237356166738e-17),
    (1.1387886347566916, 8.912812676025408e-17),
    (1.1449721444318042, 4.6412898921700107e-17),
    (1.1511892299529827, 3.250710218863827e-17),
    (1.1574400736337511, -9.1238712311344e-17),
    (1.1637248587775775, 3.8292048369240935e-17),
    (1.1700437696832502, -1.8477442017900047e-18),
    (1.1763969916502812, 5.554203254218079e-17),
    (1.182784710984341, 1.542975430079076e-17),
    (1.189207115002721, 3.982015231465646e-17),
    (1.1956643920398273, 4.6166036704814814e-17),
    (1.202156731452703, 6.644981499252301e-17),
    (1.2086843236265816, -4.746725945228984e-17),
    (1.215247359980469, -7.712630692681488e-17),
    (1.2218460329727576, -1.0611021211402691e-16),
    (1.22848053610687, -1.89878163130253e-17),
    (1.2351510639369334, -1.0755244344307841e-16),
    (1.241857812073484, 4.658027591836937e-17),
    (1.2486009771892048, -8.261810999021964e-17),
    (1.255380757024691, -6.7113898212968784e-18),
    (1.2621973503942507, -3.0844648874738465e-17),
    (1.2690509571917332, 2.667932131342186e-18),
    (1.275941778396392, 9.91543024421429e-17),
    (1.2828700160787783, 1.713594918243561e-17),
    (1.2898358734066657, 8.949257530897592e-17),
    (1.2968395546510096, 2.5382502794888315e-17),
    (1.3038812651919358, 8.647675598267871e-17),
    (1.3109612115247644, -7.181536135519454e-17),
    (1.318079601266064, -5.4579558271491535e-17),
    (1.3252366431597413, -2.8587312100388614e-17),
    (1.3324325470831615, -5.101586630916744e-17),
    (1.339667524053303, 8.927282594831732e-17),
    (1.3469417862329458, 3.224065101254679e-17),
    (1.3542555469368927, 7.70094837980299e-17),
    (1.3616090206382248, 1.533787661270668e-18),
    (1.3690024229745905, 9.593797919118849e-17),
    (1.3764359707545302, -6.898588935871801e-17),
    (1.383909881963832, -6.770511658794786e-17),
    (1.3914243757719262, -4.9061748652889893e-17),
    (1.3989796725383112, -9.614213209051323e-17),
    (1.4065759938190154, 7.034914812136422e-18),
    (1.4142135623730951, -9.667293313452913e-17),
    (1.4218926021691656, -1.6077828915890244e-17),
    (1.42961333839197, -1.2031642489053655e-17),
    (1.4373759974489824, -4.2040340164675566e-17),
    (1.4451808069770467, -3.0237581349939873e-17),
    (1.4530279958490526, -5.779948609396106e-17),
    (1.460917794180647, -5.600377186075216e-17),
    (1.4688504333369818, 8.465882756533628e-17),
    (1.4768261459394993, -3.483994556892796e-17),
    (1.4848451658727524, 1.0780086764407481e-16),
    (1.4929077282912648, 1.4192920154284036e-17),
    (1.5010140696264256, -6.413767275790235e-17),
    (1.5091644275934228, -1.016455327754295e-16),
    (1.5173590411982147, -4.308699472043341e-17),
    (1.5255981507445384, -1.1024941712342561e-16),
    (1.533881997840956, 8.875226844438446e-17),
    (1.5422108254079407, 7.949834809697621e-17),
    (1.550584877685, -1.4600706590689385e-17),
    (1.559004400237837, 3.7812070533575275e-17),
    (1.567469639965553, -1.0352061768849722e-16),
    (1.5759808451078865, -1.0136916471278304e-17),
    (1.5845382652524937, -1.9337717034585703e-17),
    (1.593142151342267, -1.0094406542311964e-16),
    (1.6017927556826934, -6.054917453527784e-17),
    (1.6104903319492543, 2.4707192569797888e-17),
    (1.6192351351948637, 2.0941334154229092e-17),
    (1.6280274218573478, -6.712955084707084e-17),
    (1.6368674497669644, 7.698325071319876e-17),
    (1.645755478153965, -1.0125679913674773e-16),
    (1.6546917676561943, 9.643294303196029e-17),
    (1.6636765803267364, 5.8909926967131e-17),
    (1.6727101796415966, -5.476715964599563e-17),
    (1.681792830507429, 8.199010020581497e-17),
    (1.6909247992693053, -9.66967147439488e-17),
    (1.7001063537185235, -8.0237193703977e-18),
    (1.709337763100463, -9.868779456632931e-17),
    (1.718619298122478, -1.851380418263111e-17),
    (1.7279512309618377, -1.0750981861204642e-16),
    (1.7373338352737062, 3.164389299292957e-17),
    (1.746767386199169, -1.0752290483507515e-16),
    (1.7562521603732995, 2.960140695448873e-17),
    (1.7657884359332727, 9.461315018083268e-17),
    (1.7753764925265212, 6.429731796556572e-17),
    (1.785016611318935, 1.5330400121031314e-17),
    (1.7947090750031072, 1.8227458427912087e-17),
    (1.804454167806624, -5.177222408793318e-17),
    (1.8142521755003989, -9.969531538920349e-17),
    (1.8241033854070534, -1.0159627862277083e-16),
    (1.8340080864093424, 3.283107224245627e-17),
    (1.843966568958626, -5.939742026949965e-17),
    (1.8539791250833855, 9.761887490727594e-17),
    (1.864046048397789, 6.540912680620572e-17),
    (1.8741676341103, -6.122763413004143e-17),
    (1.8843441790323345, -8.226593125533711e-17),
    (1.8945759815869656, 3.4034035352165297e-17),
    (1.9048633418176741, 6.533857514718279e-17),
    (1.9152065613971474, -1.0619946056195963e-16),
    (1.925605943636125, -9.914963769693741e-17),
    (1.9360617934922943, 1.0332385960676326e-16),
    (1.9465744175792332, 6.811022349533877e-17),
    (1.9571441241754002, 8.960767791036668e-17),
    (1.9677712232331759, -1.0314928011531132e-16),
    (1.978456026387951, 4.0388753109278167e-17),
    (1.9891988469672663, 8.2051326383692e-18),
];

#[cfg(test)]
mod tests {
    use super::*;

    // The algorithm's constants are what their names say.
    #[test]
    fn constants_are_ln2_over_128() {
        let ln2_n = std::f64::consts::LN_2 / 128.0;
        assert!((LN2_N_HI + LN2_N_LO - ln2_n).abs() <= ln2_n * 1e-16);
        // 36 significant bits: 17 trailing zeros.
        assert!(LN2_N_HI.to_bits().trailing_zeros() >= 17);
        assert!((INV_LN2_N * ln2_n - 1.0).abs() < 1e-15);
        assert_eq!(EXP2_TABLE[0], (1.0, 0.0));
        for (j, &(hi, lo)) in EXP2_TABLE.iter().enumerate() {
            let want = libm::exp2(j as f64 / 128.0);
            assert!((hi - want).abs() <= want * 2.3e-16, "2^({j}/128)");
            assert!(lo.abs() <= hi * 1.2e-16, "2^({j}/128) tail");
        }
    }

    // k comes from the bits of the shifted sum, negative k included.
    #[test]
    fn reduction_handles_both_signs() {
        for x in [-700.0, -3.0, -0.004, -0.0, 0.0, 0.001, 0.5, 1.0, 3.0, 700.0] {
            let (a, b) = (exp(x), libm::exp(x));
            assert!((a - b).abs() <= b * 2.3e-16, "exp({x}) = {a}, libm {b}");
        }
        assert_eq!(exp(0.0), 1.0);
    }

    // Against correctly rounded values: within 0.55 ulp means the nearest
    // f64 or its neighbour on the real value's side; and the interval
    // bounds, widened by 2 ulps, hold the real value.
    #[test]
    fn matches_correctly_rounded_values() {
        let cases = include_str!("../../tests/data/exp_cases.txt");
        let mut n = 0;
        for line in cases.lines().filter(|l| !l.starts_with('#')) {
            let f: Vec<&str> = line.split_whitespace().collect();
            let x = f64::from_bits(u64::from_str_radix(f[0], 16).unwrap());
            let cr = f64::from_bits(u64::from_str_radix(f[1], 16).unwrap());
            let side: i32 = f[2].parse().unwrap();
            let got = exp(x);
            let beside = match side {
                1 => cr.next_up(),
                -1 => cr.next_down(),
                _ => cr,
            };
            assert!(
                got == cr || got == beside,
                "exp({x:e}) = {got:e}, nearest {cr:e}"
            );
            let iv = crate::interval::Interval::point(x).exp();
            let (below, above) = match side {
                1 => (cr, cr.next_up()),
                -1 => (cr.next_down(), cr),
                _ => (cr, cr),
            };
            assert!(
                iv.lo <= below && iv.hi >= above,
                "exp({x:e}): {iv:?}, nearest {cr:e}"
            );
            n += 1;
        }
        assert!(n > 3000);
    }

    // Outside the table's range the result is libm's.
    #[test]
    fn outside_the_range_is_libm() {
        for x in [
            f64::NAN,
            f64::INFINITY,
            f64::NEG_INFINITY,
            700.5,
            -745.2,
            709.9,
            1e300,
        ] {
            let (a, b) = (exp(x), libm::exp(x));
            assert!(
                a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan()),
                "{x}"
            );
        }
    }
}
