// SPDX-License-Identifier: GPL-2.0-only OR MIT
/*
 * iec_math.c - the standard's numeric functions for REAL and LREAL without
 * libm: SQRT LN LOG EXP EXPT SIN COS TAN ASIN ACOS ATAN ATAN2.
 *
 * Floating-point object: in the kernel it is compiled with
 * -mhard-float -msse -msse2 and called only between kernel_fpu_begin() and
 * kernel_fpu_end().  It assumes IEEE 754 binary64/binary32 arithmetic in
 * SSE registers with round-to-nearest (the MXCSR default that
 * kernel_fpu_begin() loads); it uses neither long double nor x87.
 *
 * Method: the LREAL functions are written here from the textbook methods
 * (Cody-Waite and Payne-Hanek argument reduction, Taylor polynomials on
 * small reduced intervals, double-double arithmetic with Dekker's exact
 * products where the last bit matters); the REAL functions evaluate the
 * LREAL ones and round once, which makes them almost always correctly
 * rounded.
 *
 * Accuracy, measured by benchmarks/math_accuracy.py against glibc 2.36
 * (100000 random inputs per range plus an edge list; max error in ULP of
 * the reference; "exact" is mpmath at the worst input found):
 *
 *   LREAL        vs glibc  vs exact     REAL (vs glibc's double)
 *   SQRT         0         0            0.5
 *   EXP LN       1         0.67, 0.50   0.5
 *   LOG          2         0.50         0.5   (glibc's LOG10 is 1.5 off)
 *   EXPT         1         0.52         0.5
 *   SIN COS      1         0.59         0.5   (|x| up to 1e300)
 *   TAN          2         1.84         0.5
 *   ASIN ACOS    1         0.52         0.5
 *   ATAN ATAN2   1         0.53         0.5
 *
 * i.e. the REAL functions were correctly rounded on every sample.  Bounds
 * asserted by tests/runtime/test_rt_math.py.
 *
 * Domain errors give NaN (SQRT(-1), LN(-1), ASIN(2), EXPT(-8, 1/3));
 * LN(0) = -Inf; results out of range are +-Inf or 0 as IEEE 754 says.
 * No fault is raised: REAL arithmetic follows IEEE 754, the program can
 * test the result.  Special values follow C99 Annex F (e.g. EXPT(x, 0) = 1,
 * EXPT(0, -1) = +Inf, ATAN2(0, -0) = pi).
 */
#include "iec_real.h"
#include "iec_dd.h"

/*
 * x86-64: SSE2 is part of the ABI (and this file is built with -msse2 in
 * the kernel), so no __SSE2__ test: sparse does not define it.
 */
double iec__sqrt(double x)
{
#if defined(__x86_64__)
	__asm__("sqrtsd %1, %0" : "=x"(x) : "x"(x));
	return x;
#elif defined(__aarch64__)
	__asm__("fsqrt %d0, %d1" : "=w"(x) : "w"(x));
	return x;
#else
	return __builtin_sqrt(x);
#endif
}

/* ---------------------------------------------------------------------
 * EXP
 */
static const double LN2_HI = 0x1.62e42fee00000p-1;	/* 32 bits */
static const double LN2_LO = 0x1.a39ef35793c76p-33;
static const double INV_LN2 = 0x1.71547652b82fep+0;

/* exp(r) - 1 for |r| <= 0.35: Taylor polynomial to r^13. */
static inline double expm1_poly(double r)
{
	double p = 1.0 / 6227020800.0;	/* 1/13! */

	p = p * r + 1.0 / 479001600.0;
	p = p * r + 1.0 / 39916800.0;
	p = p * r + 1.0 / 3628800.0;
	p = p * r + 1.0 / 362880.0;
	p = p * r + 1.0 / 40320.0;
	p = p * r + 1.0 / 5040.0;
	p = p * r + 1.0 / 720.0;
	p = p * r + 1.0 / 120.0;
	p = p * r + 1.0 / 24.0;
	p = p * r + 1.0 / 6.0;
	p = p * r + 0.5;
	return r + r * r * p;
}

/* exp(hi + lo) with |lo| tiny against hi. */
static double exp_dd(double hi, double lo)
{
	double kd, rh, rl, p, y;
	struct iec__dd r;
	int k;

	if (iec__isnan_d(hi))
		return hi;
	if (hi > 709.782712893384)
		return IEC__INF_D;
	if (hi < -745.1332191019412)
		return 0.0;
	kd = hi * INV_LN2;
	k = (int)(kd < 0 ? kd - 0.5 : kd + 0.5);
	kd = k;
	/* r = hi + lo - k ln2 as rh + rl with |rl| <= ulp(rh) / 2:
	 * exp(r) = exp(rh) (1 + rl) */
	r = iec__two_sum(hi - kd * LN2_HI, lo - kd * LN2_LO);
	rh = r.hi;
	rl = r.lo;
	p = expm1_poly(rh);
	y = 1.0 + (p + rl * (1.0 + p));
	return iec__scalbn_d(y, k);
}

double iec_exp_lreal(double x)
{
	return exp_dd(x, 0.0);
}

/* ---------------------------------------------------------------------
 * LN, LOG
 *
 * x = 2^k * m with m in [1, 1.5) or [0.75, 1); a table gives c near m
 * (as 1/c, exactly, and ln(c) as a double-double), f = m/c - 1 is computed
 * exactly with Dekker's product and |f| <= 2^-7, so
 * ln(x) = k ln2 + ln(c) + ln(1 + f) with a short series for ln(1 + f).
 * The result is a double-double good to about 2^-70 (used by LOG and EXPT).
 */
struct iec__logc {
	double inv_c, lnc_hi, lnc_lo;
};

/* index: the top 7 bits of the mantissa; entries 64..127 are for m / 2 */
static const struct iec__logc LOG_TAB[128] = {
	{ 0x1.0000000000000p+0, 0x0.0p+0, 0x0.0p+0 },
	{ 0x1.fa11caa01fa12p-1, 0x1.7dc475f810a69p-7, 0x1.74944bc161072p-61 },
	{ 0x1.f6310aca0dbb5p-1, 0x1.3cea44346a584p-6, -0x1.865ad48159d00p-61 },
	{ 0x1.f25f644230ab5p-1, 0x1.b9fc027af919ap-6, -0x1.90ae69229dc86p-60 },
	{ 0x1.ee9c7f8458e02p-1, 0x1.1b0d98923d97fp-5, -0x1.74d7444dd6241p-59 },
	{ 0x1.eae807aba01ebp-1, 0x1.58a5bafc8e4d3p-5, -0x1.cab8569c56e40p-64 },
	{ 0x1.e741aa59750e4p-1, 0x1.95c830ec8e3f2p-5, 0x1.eb41d00a417e9p-60 },
	{ 0x1.e3a9179dc1a73p-1, 0x1.d276b8adb0b56p-5, 0x1.078f14c95ff53p-59 },
	{ 0x1.e01e01e01e01ep-1, 0x1.075983598e471p-4, 0x1.006d2999e22dcp-58 },
	{ 0x1.dca01dca01dcap-1, 0x1.253f62f0a1417p-4, 0x1.1f6d34e01d981p-61 },
	{ 0x1.d92f2231e7f8ap-1, 0x1.42edcbea646eep-4, -0x1.511583653349bp-58 },
	{ 0x1.d5cac807572b2p-1, 0x1.60658a93750c4p-4, -0x1.f108b1d8436d3p-59 },
	{ 0x1.d272ca3fc5b1ap-1, 0x1.7da766d7b12d0p-4, 0x1.a2240644d7da2p-59 },
	{ 0x1.cf26e5c44bfc6p-1, 0x1.9ab42462033aep-4, -0x1.a099e1c184e8ep-59 },
	{ 0x1.cbe6d9601cbe7p-1, 0x1.b78c82bb0eda0p-4, -0x1.3ef0e61f9b03cp-58 },
	{ 0x1.c8b265afb8a42p-1, 0x1.d4313d66cb35dp-4, 0x1.b90dd951d90fap-58 },
	{ 0x1.c5894d10d4986p-1, 0x1.f0a30c01162a4p-4, 0x1.8be64b8b7759bp-59 },
	{ 0x1.c26b5392ea01cp-1, 0x1.0671512ca596fp-3, -0x1.2f39b81479b67p-58 },
	{ 0x1.bf583ee868d8bp-1, 0x1.14785846742acp-3, 0x1.94409f1d3f83ap-60 },
	{ 0x1.bc4fd65883e7bp-1, 0x1.2266f190a5acdp-3, -0x1.dab840e7f6177p-57 },
	{ 0x1.b951e2b18ff23p-1, 0x1.303d718e47fd5p-3, -0x1.b5ae71f658247p-57 },
	{ 0x1.b65e2e3beee05p-1, 0x1.3dfc2b0ecc62ap-3, 0x1.ba62b8c13f7f4p-57 },
	{ 0x1.b37484ad806cep-1, 0x1.4ba36f39a55e5p-3, -0x1.f767e433c98aap-57 },
	{ 0x1.b094b31d922a4p-1, 0x1.59338d9982085p-3, 0x1.8d16eaaba9419p-57 },
	{ 0x1.adbe87f94905ep-1, 0x1.66acd4272ad51p-3, -0x1.9201c9c3d5165p-59 },
	{ 0x1.aaf1d2f87ebfdp-1, 0x1.740f8f54037a3p-3, 0x1.6d9bf9d57b326p-58 },
	{ 0x1.a82e65130e159p-1, 0x1.815c0a14357e9p-3, 0x1.141b7f8c5fa9ep-58 },
	{ 0x1.a574107688a4ap-1, 0x1.8e928de886d41p-3, 0x1.2589eb96a6240p-59 },
	{ 0x1.a2c2a87c51ca0p-1, 0x1.9bb362e7dfb85p-3, -0x1.51439c1ff83e7p-58 },
	{ 0x1.a01a01a01a01ap-1, 0x1.a8becfc882f19p-3, -0x1.a8c37918c39ebp-58 },
	{ 0x1.9d79f176b682dp-1, 0x1.b5b519e8fb5a6p-3, -0x1.d5d8023e61e5fp-57 },
	{ 0x1.9ae24ea5510dap-1, 0x1.c2968558c18c2p-3, 0x1.6108e3ae024acp-60 },
	{ 0x1.9852f0d8ec0ffp-1, 0x1.cf6354e09c5ddp-3, 0x1.339a07d55b696p-57 },
	{ 0x1.95cbb0be377aep-1, 0x1.dc1bca0abec7bp-3, 0x1.c698a33316dfbp-58 },
	{ 0x1.934c67f9b2ce6p-1, 0x1.e8c0252aa5a60p-3, -0x1.dc074737f9135p-60 },
	{ 0x1.90d4f120190d5p-1, 0x1.f550a564b7b37p-3, -0x1.13a09202fe73dp-57 },
	{ 0x1.8e6527af1373fp-1, 0x1.00e6c45ad501dp-2, -0x1.3b9568ff6feadp-57 },
	{ 0x1.8bfce8062ff3ap-1, 0x1.071b85fcd590dp-2, 0x1.08b83fcbdef40p-57 },
	{ 0x1.899c0f601899cp-1, 0x1.0d46b579ab74bp-2, 0x1.21f640e1e5ec9p-56 },
	{ 0x1.87427bcc092b9p-1, 0x1.136870293a8b0p-2, 0x1.86cc531dba494p-57 },
	{ 0x1.84f00c2780614p-1, 0x1.1980d2dd4236fp-2, -0x1.02c2e4f1b2eb9p-56 },
	{ 0x1.82a4a0182a4a0p-1, 0x1.1f8ff9e48a2f3p-2, -0x1.93fbf3418960dp-57 },
	{ 0x1.8060180601806p-1, 0x1.2596010df763ap-2, -0x1.9eed8ae0ebd3cp-59 },
	{ 0x1.7e225515a4f1dp-1, 0x1.2b9303ab89d25p-2, -0x1.85ad7f614ab51p-58 },
	{ 0x1.7beb3922e017cp-1, 0x1.31871c9544185p-2, -0x1.ea3598981366fp-57 },
	{ 0x1.79baa6bb6398bp-1, 0x1.3772662bfd85cp-2, 0x1.02a7589fba088p-57 },
	{ 0x1.77908119ac60dp-1, 0x1.3d54fa5c1f710p-2, 0x1.53668e578d9cdp-58 },
	{ 0x1.756cac201756dp-1, 0x1.432ef2a04e813p-2, -0x1.83262e2b59206p-57 },
	{ 0x1.734f0c541fe8dp-1, 0x1.49006804009d0p-2, -0x1.bff0d07c5df6dp-59 },
	{ 0x1.713786d9c7c09p-1, 0x1.4ec9732600269p-2, -0x1.1aa87d977dc5ep-56 },
	{ 0x1.6f26016f26017p-1, 0x1.548a2c3add263p-2, -0x1.58ce7bf1846eep-56 },
	{ 0x1.6d1a62681c861p-1, 0x1.5a42ab0f4cfe2p-2, -0x1.c6bcb7dee9a3dp-56 },
	{ 0x1.6b1490aa31a3dp-1, 0x1.5ff3070a793d4p-2, -0x1.063077d7e37b7p-56 },
	{ 0x1.691473a88d0c0p-1, 0x1.659b57303e1f2p-2, 0x1.db0af8efb83c7p-62 },
	{ 0x1.6719f3601671ap-1, 0x1.6b3bb2235943dp-2, 0x1.957a93326784dp-56 },
	{ 0x1.6524f853b4aa3p-1, 0x1.70d42e2789236p-2, 0x1.ee99bf7143954p-56 },
	{ 0x1.63356b88ac0dep-1, 0x1.7664e1239dbcfp-2, -0x1.d6d5d64f5daf8p-57 },
	{ 0x1.614b36831ae94p-1, 0x1.7bede0a37afbfp-2, -0x1.6783cb9801a5bp-56 },
	{ 0x1.5f66434292dfcp-1, 0x1.816f41da0d495p-2, 0x1.76dc35fb48fe4p-56 },
	{ 0x1.5d867c3ece2a5p-1, 0x1.86e919a330ba1p-2, -0x1.700c9d2029045p-56 },
	{ 0x1.5babcc647fa91p-1, 0x1.8c5b7c858b48bp-2, 0x1.d754b0205fa6cp-56 },
	{ 0x1.59d61f123ccaap-1, 0x1.91c67eb45a83ep-2, 0x1.5e3ea3b96a3dfp-57 },
	{ 0x1.5805601580560p-1, 0x1.972a341135159p-2, -0x1.5a3f62db48f27p-56 },
	{ 0x1.56397ba7c52e2p-1, 0x1.9c86b02dc0862p-2, 0x1.7e81149622bdfp-56 },
	{ 0x1.54725e6bb82fep+0, -0x1.23ec5991eba49p-2, -0x1.76eba35bbf0dfp-61 },
	{ 0x1.52aff56a8054bp+0, -0x1.1e9e1678899f5p-2, -0x1.64b0dd2687939p-58 },
	{ 0x1.50f22e111c4c5p+0, -0x1.1956d3b9bc2f9p-2, -0x1.0e75a3542856fp-58 },
	{ 0x1.4f38f62dd4c9bp+0, -0x1.14167ef367784p-2, -0x1.ef824daaf53e9p-56 },
	{ 0x1.4d843bedc2c4cp+0, -0x1.0edd060b78082p-2, -0x1.2d4b610d7d4f5p-57 },
	{ 0x1.4bd3edda68fe1p+0, -0x1.09aa572e6c6d4p-2, -0x1.f9e17343426a9p-56 },
	{ 0x1.4a27fad76014ap+0, -0x1.047e60cde83b7p-2, -0x1.08869cbf9e344p-56 },
	{ 0x1.4880522014880p+0, -0x1.feb2233ea07cbp-3, -0x1.8de00938b4c30p-61 },
	{ 0x1.46dce34596066p+0, -0x1.f474b134df228p-3, 0x1.9f1df7b5daab7p-60 },
	{ 0x1.453d9e2c776cap+0, -0x1.ea4449f04aaf5p-3, 0x1.f33919ab94074p-57 },
	{ 0x1.43a2730abee4dp+0, -0x1.e020cc6235ab5p-3, 0x1.f0adb91423f18p-57 },
	{ 0x1.420b5265e5951p+0, -0x1.d60a17f903514p-3, 0x1.50df841a71b7ap-57 },
	{ 0x1.40782d10e6566p+0, -0x1.cc000c9db3c52p-3, -0x1.67a2a8500729ep-58 },
	{ 0x1.3ee8f42a5af07p+0, -0x1.c2028ab17f9b5p-3, -0x1.c11aa3853a5f0p-57 },
	{ 0x1.3d5d991aa75c6p+0, -0x1.b811730b823d4p-3, 0x1.d7c46328983c6p-58 },
	{ 0x1.3bd60d9232955p+0, -0x1.ae2ca6f672bd8p-3, 0x1.a4a356155f779p-57 },
	{ 0x1.3a524387ac822p+0, -0x1.a454082e6ab03p-3, 0x1.e0df823a3cb3dp-58 },
	{ 0x1.38d22d366088ep+0, -0x1.9a8778debaa3ap-3, -0x1.28fbfb0e3f0fcp-58 },
	{ 0x1.3755bd1c945eep+0, -0x1.90c6db9fcbcdbp-3, 0x1.357718d7ca4cfp-58 },
	{ 0x1.35dce5f9f2af8p+0, -0x1.871213750e994p-3, 0x1.a97a0ca115d60p-57 },
	{ 0x1.34679ace01346p+0, -0x1.7d6903caf5acdp-3, 0x1.0b17c301d6e14p-57 },
	{ 0x1.32f5ced6a1dfap+0, -0x1.73cb9074fd14dp-3, 0x1.721a000b4cf01p-57 },
	{ 0x1.3187758e9ebb6p+0, -0x1.6a399dabbd383p-3, -0x1.76332bd4b341fp-57 },
	{ 0x1.301c82ac40260p+0, -0x1.60b3100b09474p-3, -0x1.526cee0fd7f4ap-57 },
	{ 0x1.2eb4ea1fed14bp+0, -0x1.5737cc9018cddp-3, 0x1.00b28ef013c72p-57 },
	{ 0x1.2d50a012d50a0p+0, -0x1.4dc7b897bc1c7p-3, -0x1.b60ae1ff0e82ep-59 },
	{ 0x1.2bef98e5a3711p+0, -0x1.4462b9dc9b3dcp-3, 0x1.85388d830c709p-59 },
	{ 0x1.2a91c92f3c105p+0, -0x1.3b08b6757f2a7p-3, -0x1.5e1ad9be0a4cdp-57 },
	{ 0x1.293725bb804a5p+0, -0x1.31b994d3a4f86p-3, 0x1.1238b5efe0665p-57 },
	{ 0x1.27dfa38a1ce4dp+0, -0x1.28753bc11aba2p-3, 0x1.7394d9fa33313p-57 },
	{ 0x1.268b37cd60127p+0, -0x1.1f3b925f25d44p-3, -0x1.08b27be4e6b15p-57 },
	{ 0x1.2539d7e9177b2p+0, -0x1.160c8024b27b0p-3, 0x1.355bfd870afebp-59 },
	{ 0x1.23eb79717605bp+0, -0x1.0ce7ecdccc28bp-3, -0x1.1b57fea88da98p-59 },
	{ 0x1.22a0122a0122ap+0, -0x1.03cdc0a51ec0dp-3, -0x1.19e2d3f8b7d10p-57 },
	{ 0x1.21579804855e6p+0, -0x1.f57bc7d9005dbp-4, 0x1.d361574fb24e2p-58 },
	{ 0x1.2012012012012p+0, -0x1.e3707ee30487bp-4, -0x1.9399d9aaf3b33p-59 },
	{ 0x1.1ecf43c7fb84cp+0, -0x1.d179788219362p-4, 0x1.b12841044a96cp-58 },
	{ 0x1.1d8f5672e4abdp+0, -0x1.bf968769fca18p-4, 0x1.06e4fb7af9c69p-58 },
	{ 0x1.1c522fc1ce059p+0, -0x1.adc77ee5aea8ep-4, -0x1.d7d8f39bee658p-58 },
	{ 0x1.1b17c67f2bae3p+0, -0x1.9c0c32d4d254dp-4, 0x1.627a0e199f569p-58 },
	{ 0x1.19e0119e0119ep+0, -0x1.8a6477a91dc29p-4, 0x1.3d4190a482421p-58 },
	{ 0x1.18ab083902bdbp+0, -0x1.78d02263d82d7p-4, -0x1.cbca5b4fdb87ep-58 },
	{ 0x1.1778a191bd684p+0, -0x1.674f089365a78p-4, -0x1.ca64e9980e048p-59 },
	{ 0x1.1648d50fc3201p+0, -0x1.55e10050e0382p-4, -0x1.9a0629e3973e4p-58 },
	{ 0x1.151b9a3fdd5c9p+0, -0x1.4485e03dbdfb0p-4, -0x1.3ba349aadbc6dp-58 },
	{ 0x1.13f0e8d344724p+0, -0x1.333d7f8183f4ap-4, 0x1.adaa06e211e9ep-59 },
	{ 0x1.12c8b89edc0acp+0, -0x1.2207b5c7854a1p-4, -0x1.b3f0431efb154p-58 },
	{ 0x1.11a3019a74826p+0, -0x1.10e45b3cae829p-4, -0x1.9b5ed72e6d974p-58 },
	{ 0x1.107fbbe011080p+0, -0x1.ffa6911ab9309p-5, 0x1.cd9f1f95c2ef1p-59 },
	{ 0x1.0f5edfab325a2p+0, -0x1.dda8adc67ee59p-5, 0x1.31936790bb3b2p-59 },
	{ 0x1.0e40655826011p+0, -0x1.bbcebfc68f424p-5, 0x1.cd1862f854848p-59 },
	{ 0x1.0d24456359e3ap+0, -0x1.9a187b573de81p-5, -0x1.b13b26f298a6ap-64 },
	{ 0x1.0c0a7868b4171p+0, -0x1.788595a3577c8p-5, -0x1.2f7c4c5b3c8bdp-62 },
	{ 0x1.0af2f722eecb5p+0, -0x1.5715c4c03cee1p-5, -0x1.5101dc4ebf91fp-59 },
	{ 0x1.09ddba6af8360p+0, -0x1.35c8bfaa13069p-5, 0x1.50830a65543a8p-63 },
	{ 0x1.08cabb37565e2p+0, -0x1.149e3e4005a8dp-5, 0x1.a9a4168fcebebp-60 },
	{ 0x1.07b9f29b8eae2p+0, -0x1.e72bf2813ce6ap-6, 0x1.8a4bba6a354fap-60 },
	{ 0x1.06ab59c7912fbp+0, -0x1.a55f548c5c427p-6, -0x1.f60d2fc36a0d9p-61 },
	{ 0x1.059eea0727586p+0, -0x1.63d6178690bbep-6, 0x1.18ed4d357c9dcp-60 },
	{ 0x1.04949cc1664c5p+0, -0x1.228fb1fea2e0ap-6, -0x1.3284991fe3d5cp-61 },
	{ 0x1.038c6b78247fcp+0, -0x1.c317384c75f0dp-7, -0x1.806208c04c21fp-61 },
	{ 0x1.02864fc7729e9p+0, -0x1.41929f968330cp-7, -0x1.3aae809b43dd0p-61 },
	{ 0x1.0182436517a37p+0, -0x1.8121214586b02p-8, 0x1.c7d68c0d910f2p-62 },
	{ 0x1.0000000000000p+0, 0x0.0p+0, 0x0.0p+0 },
};

/* ln(1 + f) - f + f^2/2 for |f| <= 2^-7: f^3/3 - f^4/4 + ... - f^12/12 */
static inline double log1p_tail(double f)
{
	double p = -1.0 / 12;

	p = p * f + 1.0 / 11;
	p = p * f - 1.0 / 10;
	p = p * f + 1.0 / 9;
	p = p * f - 1.0 / 8;
	p = p * f + 1.0 / 7;
	p = p * f - 1.0 / 6;
	p = p * f + 1.0 / 5;
	p = p * f - 1.0 / 4;
	p = p * f + 1.0 / 3;
	return p * f * f * f;
}

/* ln(x) as a double-double, for finite x > 0. */
static struct iec__dd ln_dd(double x)
{
	iec_u64 u = iec__asu64(x);
	int k = 0, j;
	double m, kd, lo;
	struct iec__dd p, f, sq, a, b, c;

	if (u < (1ULL << 52)) {		/* subnormal */
		x *= 0x1p54;
		u = iec__asu64(x);
		k = -54;
	}
	k += (int)(u >> 52) - 1023;
	j = (int)((u >> 45) & 127);
	m = iec__asdouble((u & ((1ULL << 52) - 1)) | 0x3ff0000000000000ULL);
	if (j >= 64) {
		m *= 0.5;
		k++;
	}
	kd = k;
	p = iec__two_prod(m, LOG_TAB[j].inv_c);
	f = iec__two_sum(p.hi - 1.0, p.lo);		/* p.hi - 1 is exact */
	sq = iec__two_prod(f.hi, f.hi);
	a = iec__two_sum(kd * LN2_HI, LOG_TAB[j].lnc_hi);
	b = iec__two_sum(a.hi, f.hi);
	c = iec__two_sum(b.hi, -0.5 * sq.hi);
	lo = a.lo + b.lo + c.lo + LOG_TAB[j].lnc_lo + kd * LN2_LO + f.lo -
	     0.5 * sq.lo - f.hi * f.lo + log1p_tail(f.hi);
	return iec__fast_two_sum(c.hi, lo);
}

double iec_ln_lreal(double x)
{
	struct iec__dd r;

	if (iec__isnan_d(x))
		return x;
	if (x < 0)
		return IEC__NAN_D;
	if (x == 0)
		return -IEC__INF_D;
	if (x == IEC__INF_D)
		return x;
	r = ln_dd(x);
	return r.hi + r.lo;
}

double iec_log_lreal(double x)
{
	static const struct iec__dd ivln10 = {
		0x1.bcb7b1526e50ep-2, 0x1.95355baaafad3p-57
	};
	struct iec__dd r;

	if (iec__isnan_d(x))
		return x;
	if (x < 0)
		return IEC__NAN_D;
	if (x == 0)
		return -IEC__INF_D;
	if (x == IEC__INF_D)
		return x;
	r = iec__dd_mul(ln_dd(x), ivln10);
	return r.hi + r.lo;
}

/* ---------------------------------------------------------------------
 * EXPT (x ** y)
 */
static int is_integer(double y)
{
	if (iec__fabs_d(y) >= 0x1p52)
		return 1;
	return y == (double)(iec_s64)y;
}

static int is_odd_integer(double y)
{
	if (iec__fabs_d(y) >= 0x1p53 || !is_integer(y))
		return 0;
	return (int)((iec_s64)y & 1);
}

double iec_expt_lreal(double x, double y)
{
	struct iec__dd l;
	double ax = iec__fabs_d(x), r;
	int neg = 0;

	if (y == 0 || x == 1)
		return 1.0;
	if (iec__isnan_d(x) || iec__isnan_d(y))
		return IEC__NAN_D;
	if (iec__asu64(x) >> 63) {			/* x < 0, -0 or -Inf */
		if (!is_integer(y)) {
			if (ax == 0 || ax == IEC__INF_D || y == IEC__INF_D ||
			    y == -IEC__INF_D)
				neg = 0;	/* C99: as for |x| */
			else
				return IEC__NAN_D;
		} else {
			neg = is_odd_integer(y);
		}
	}
	if (ax == 1)				/* (-1) ** y, y integer or Inf */
		return neg ? -1.0 : 1.0;
	if (ax == 0 || ax == IEC__INF_D) {
		r = (ax == 0) == (y < 0) ? IEC__INF_D : 0.0;
		return neg ? -r : r;
	}
	/* |y| > 2^64 and |x| != 1: |y ln x| > 2^11, so Inf or 0 */
	if (iec__fabs_d(y) > 0x1p64)
		return (ax < 1) == (y > 0) ? 0.0 : IEC__INF_D;
	l = iec__dd_mul_d(ln_dd(ax), y);
	r = exp_dd(l.hi, l.lo);
	return neg ? -r : r;
}

/* ---------------------------------------------------------------------
 * Argument reduction for SIN, COS, TAN: x = n pi/2 + r, |r| <= pi/4,
 * r returned as a double-double, n mod 4 as the result.
 */
static const double PIO2_1 = 0x1.921fb54400000p+0;	/* 33 bits */
static const double PIO2_2 = 0x1.0b4611a600000p-34;	/* 33 bits */
static const double PIO2_3 = 0x1.3198a2e000000p-69;	/* 33 bits */
static const double PIO2_4 = 0x1.b839a252049c1p-104;
static const struct iec__dd PIO2 = {
	0x1.921fb54442d18p+0, 0x1.1a62633145c07p-54
};
static const double INV_PIO2 = 0x1.45f306dc9c883p-1;

/* 2/pi: word j holds bits 64j+1 .. 64j+64 after the binary point. */
static const iec_u64 TWO_OVER_PI[20] = {
	0xa2f9836e4e441529ull, 0xfc2757d1f534ddc0ull,
	0xdb6295993c439041ull, 0xfe5163abdebbc561ull,
	0xb7246e3a424dd2e0ull, 0x06492eea09d1921cull,
	0xfe1deb1cb129a73eull, 0xe88235f52ebb4484ull,
	0xe99c7026b45f7e41ull, 0x3991d639835339f4ull,
	0x9c845f8bbdf9283bull, 0x1ff897ffde05980full,
	0xef2f118b5a0a6d1full, 0x6d367ecf27cb09b7ull,
	0x4f463f669e5fea2dull, 0x7527bac7ebe5f17bull,
	0x3d0739f78a5292eaull, 0x6bfb5fb11f8d5d08ull,
	0x56033046fc7b6babull, 0xf0cfbc209af4361dull,
};

/* 64 bits of 2/pi starting at bit pos (1-based; bits at pos <= 0 are the
 * integer part of 2/pi, which is 0). */
static iec_u64 two_over_pi_bits(int pos)
{
	iec_u64 hi, lo;
	int w, sh;

	if (pos <= -63)
		return 0;
	if (pos <= 0)
		return TWO_OVER_PI[0] >> (1 - pos);
	w = (pos - 1) / 64;
	sh = (pos - 1) % 64;
	hi = TWO_OVER_PI[w];
	lo = w + 1 < 20 ? TWO_OVER_PI[w + 1] : 0;
	return sh ? (hi << sh) | (lo >> (64 - sh)) : hi;
}

/* Payne-Hanek reduction for |x| >= 2^20 (finite). */
static int rem_pio2_large(double x, struct iec__dd *r)
{
	typedef unsigned __int128 u128;
	iec_u64 u = iec__asu64(x), m, w0, w1, w2, p1, p2, p3, fhi, flo, c;
	int e = (int)((u >> 52) & 0x7ff) - 1075;	/* x = m * 2^e */
	int n, neg = 0, lz;
	u128 t;
	double a, b;
	struct iec__dd f;

	m = (u & ((1ULL << 52) - 1)) | (1ULL << 52);
	/* bits e-1 .. e+190 of 2/pi: the product's binary point is 190 bits
	 * up, higher bits only add multiples of 4 */
	w0 = two_over_pi_bits(e - 1);
	w1 = two_over_pi_bits(e + 63);
	w2 = two_over_pi_bits(e + 127);
	t = (u128)m * w2;
	p3 = (iec_u64)t;
	c = (iec_u64)(t >> 64);
	t = (u128)m * w1 + c;
	p2 = (iec_u64)t;
	c = (iec_u64)(t >> 64);
	t = (u128)m * w0 + c;
	p1 = (iec_u64)t;
	/* integer part mod 4: bits 190, 191 = bits 62, 63 of p1 */
	n = (int)(p1 >> 62);
	fhi = (p1 << 2) | (p2 >> 62);
	flo = (p2 << 2) | (p3 >> 62);
	if (fhi >> 63) {			/* fraction >= 1/2 */
		n++;
		neg = 1;
		fhi = ~fhi;
		flo = ~flo + 1;
		if (!flo)
			fhi++;
	}
	if (!fhi && !flo) {
		r->hi = r->lo = 0;
		return n & 3;
	}
	lz = fhi ? __builtin_clzll(fhi) : 64 + __builtin_clzll(flo);
	if (lz >= 64) {
		fhi = flo << (lz - 64);
		flo = 0;
	} else if (lz) {
		fhi = (fhi << lz) | (flo >> (64 - lz));
		flo <<= lz;
	}
	/* fraction = (fhi * 2^-64 + flo * 2^-128) * 2^-lz */
	a = (double)(fhi >> 11) * 0x1p-53;
	b = ((double)(fhi & 0x7ff) * 0x1p-64 + (double)(flo >> 11) * 0x1p-117);
	f = iec__fast_two_sum(a, b);
	f.hi = iec__scalbn_d(f.hi, -lz);
	f.lo = iec__scalbn_d(f.lo, -lz);
	f = iec__dd_mul(f, PIO2);
	if (x < 0) {
		neg = !neg;
		n = -n;
	}
	if (neg) {
		f.hi = -f.hi;
		f.lo = -f.lo;
	}
	*r = f;
	return n & 3;
}

static int rem_pio2(double x, struct iec__dd *r)
{
	double kd, t;
	struct iec__dd s;
	int n;

	if (iec__fabs_d(x) <= 0x1.921fb54442d18p-1) {	/* pi/4 */
		r->hi = x;
		r->lo = 0;
		return 0;
	}
	if (iec__fabs_d(x) >= 0x1p20)
		return rem_pio2_large(x, r);
	kd = x * INV_PIO2;
	n = (int)(kd < 0 ? kd - 0.5 : kd + 0.5);
	kd = n;
	t = x - kd * PIO2_1;			/* exact */
	s = iec__two_sum(t, -kd * PIO2_2);		/* kd * PIO2_2 exact */
	s = iec__dd_add(s, (struct iec__dd){ -kd * PIO2_3, -kd * PIO2_4 });
	*r = s;
	return n & 3;
}

/* sin and cos on |r| <= pi/4 (+ the tail rl): Taylor to r^19 / r^20. */
static double sin_k(double x, double xl)
{
	double z = x * x, p;

	p = -1.0 / 121645100408832000.0;	/* -1/19! */
	p = p * z + 1.0 / 355687428096000.0;
	p = p * z - 1.0 / 1307674368000.0;
	p = p * z + 1.0 / 6227020800.0;
	p = p * z - 1.0 / 39916800.0;
	p = p * z + 1.0 / 362880.0;
	p = p * z - 1.0 / 5040.0;
	p = p * z + 1.0 / 120.0;
	p = p * z - 1.0 / 6.0;
	return x + (x * z * p + xl * (1.0 - 0.5 * z));
}

static double cos_k(double x, double xl)
{
	double z = x * x, q, hz, w;

	q = 1.0 / 2432902008176640000.0;	/* 1/20! */
	q = q * z - 1.0 / 6402373705728000.0;
	q = q * z + 1.0 / 20922789888000.0;
	q = q * z - 1.0 / 87178291200.0;
	q = q * z + 1.0 / 479001600.0;
	q = q * z - 1.0 / 3628800.0;
	q = q * z + 1.0 / 40320.0;
	q = q * z - 1.0 / 720.0;
	q = q * z + 1.0 / 24.0;
	hz = 0.5 * z;
	w = 1.0 - hz;
	return w + (((1.0 - w) - hz) + (z * z * q - x * xl));
}

double iec_sin_lreal(double x)
{
	struct iec__dd r;

	if (iec__isnan_d(x) || x == IEC__INF_D || x == -IEC__INF_D)
		return IEC__NAN_D;
	switch (rem_pio2(x, &r)) {
	case 0:
		return sin_k(r.hi, r.lo);
	case 1:
		return cos_k(r.hi, r.lo);
	case 2:
		return -sin_k(r.hi, r.lo);
	default:
		return -cos_k(r.hi, r.lo);
	}
}

double iec_cos_lreal(double x)
{
	struct iec__dd r;

	if (iec__isnan_d(x) || x == IEC__INF_D || x == -IEC__INF_D)
		return IEC__NAN_D;
	switch (rem_pio2(x, &r)) {
	case 0:
		return cos_k(r.hi, r.lo);
	case 1:
		return -sin_k(r.hi, r.lo);
	case 2:
		return -cos_k(r.hi, r.lo);
	default:
		return sin_k(r.hi, r.lo);
	}
}

double iec_tan_lreal(double x)
{
	struct iec__dd r, s, c;
	int n;

	if (iec__isnan_d(x) || x == IEC__INF_D || x == -IEC__INF_D)
		return IEC__NAN_D;
	n = rem_pio2(x, &r);
	if (r.hi == 0 && r.lo == 0)
		return (n & 1) ? -IEC__INF_D : iec__copysign_d(0.0, x);
	/* sin and cos as double-doubles would cost more than this is worth:
	 * the quotient of the two correctly rounded kernels */
	s.hi = sin_k(r.hi, r.lo);
	s.lo = 0;
	c.hi = cos_k(r.hi, r.lo);
	c.lo = 0;
	if (n & 1) {
		s = iec__dd_div(c, s);
		return -(s.hi + s.lo);
	}
	s = iec__dd_div(s, c);
	return s.hi + s.lo;
}

/* ---------------------------------------------------------------------
 * ATAN, ATAN2, ASIN, ACOS
 */
static const struct iec__dd ATAN_TAB[17] = {
	{ 0x0.0p+0, 0x0.0p+0 },
	{ 0x1.ff55bb72cfdeap-5, -0x1.c934d86d23f1dp-60 },
	{ 0x1.fd5ba9aac2f6ep-4, -0x1.cd37686760c17p-59 },
	{ 0x1.7b97b4bce5b02p-3, 0x1.347b0b4f881cap-58 },
	{ 0x1.f5b75f92c80ddp-3, 0x1.8ab6e3cf7afbdp-57 },
	{ 0x1.362773707ebccp-2, -0x1.963a544b672d8p-57 },
	{ 0x1.6f61941e4def1p-2, -0x1.c63aae6f6e918p-56 },
	{ 0x1.a64eec3cc23fdp-2, -0x1.24dec1b50b7ffp-56 },
	{ 0x1.dac670561bb4fp-2, 0x1.a2b7f222f65e2p-56 },
	{ 0x1.0657e94db30d0p-1, -0x1.d5b495f6349e6p-56 },
	{ 0x1.1e00babdefeb4p-1, -0x1.928df287a668fp-58 },
	{ 0x1.345f01cce37bbp-1, 0x1.1021137c71102p-55 },
	{ 0x1.4978fa3269ee1p-1, 0x1.2419a87f2a458p-56 },
	{ 0x1.5d58987169b18p-1, 0x1.0028e4bc5e7cap-57 },
	{ 0x1.700a7c5784634p-1, -0x1.8c34d25aadef6p-56 },
	{ 0x1.819d0b7158a4dp-1, -0x1.bf76229d3b917p-56 },
	{ 0x1.921fb54442d18p-1, 0x1.1a62633145c07p-55 },
};

/* atan(t) for |t| <= 1/32 (+ the tail tl): Taylor to t^13. */
static double atan_poly(double t, double tl)
{
	double z = t * t, p;

	p = 1.0 / 13;
	p = p * z - 1.0 / 11;
	p = p * z + 1.0 / 9;
	p = p * z - 1.0 / 7;
	p = p * z + 1.0 / 5;
	p = p * z - 1.0 / 3;
	return t + (t * z * p + tl * (1.0 - z));
}

/* atan(a) for 0 <= a <= 1 as a double-double. */
static struct iec__dd atan01(double a, double al)
{
	int k = (int)(a * 16 + 0.5);
	double c = k * 0.0625, num;
	struct iec__dd q, r;

	if (k == 0) {
		r.hi = atan_poly(a, al);
		r.lo = 0;
		return r;
	}
	/* atan(a) = atan(c) + atan((a - c) / (1 + a c)), a - c exact */
	num = a - c;
	q = iec__dd_div((struct iec__dd){ num, al },
		   iec__dd_add((struct iec__dd){ 1.0, 0 }, iec__two_prod(a, c)));
	r = iec__two_sum(ATAN_TAB[k].hi, atan_poly(q.hi, q.lo));
	r.lo += ATAN_TAB[k].lo;
	return iec__fast_two_sum(r.hi, r.lo);
}

/* atan(y / x) for x > 0, y >= 0, finite, as a double-double. */
static struct iec__dd atan_pos(double y, double x)
{
	struct iec__dd q, r;

	if (y <= x) {
		q = iec__dd_div((struct iec__dd){ y, 0 }, (struct iec__dd){ x, 0 });
		return atan01(q.hi, q.lo);
	}
	q = iec__dd_div((struct iec__dd){ x, 0 }, (struct iec__dd){ y, 0 });
	r = atan01(q.hi, q.lo);
	return iec__dd_add(PIO2, (struct iec__dd){ -r.hi, -r.lo });
}

double iec_atan_lreal(double x)
{
	struct iec__dd r;
	double a = iec__fabs_d(x);

	if (iec__isnan_d(x))
		return x;
	if (a > 0x1p66)
		return iec__copysign_d(PIO2.hi, x);
	if (a < 0x1p-30)
		return x;
	r = a <= 1 ? atan01(a, 0) : atan_pos(a, 1.0);
	return iec__copysign_d(r.hi + r.lo, x);
}

double iec_atan2_lreal(double y, double x)
{
	static const struct iec__dd pi = { 0x1.921fb54442d18p+1,
				      0x1.1a62633145c07p-53 };
	double ay = iec__fabs_d(y), ax = iec__fabs_d(x), v;
	int xneg = (iec__asu64(x) >> 63) != 0;
	struct iec__dd r;

	if (iec__isnan_d(x) || iec__isnan_d(y))
		return IEC__NAN_D;
	if (y == 0)
		return xneg ? iec__copysign_d(pi.hi, y) : y;
	if (x == 0)
		return iec__copysign_d(PIO2.hi, y);
	if (ax == IEC__INF_D) {
		if (ay == IEC__INF_D)
			v = xneg ? 3 * 0x1.921fb54442d18p-1 : 0x1.921fb54442d18p-1;
		else
			v = xneg ? pi.hi : 0.0;
		return iec__copysign_d(v, y);
	}
	if (ay == IEC__INF_D)
		return iec__copysign_d(PIO2.hi, y);
	/* scale so that neither the quotient nor the products overflow */
	if (ax > 0x1p1000 || ay > 0x1p1000) {
		ax *= 0x1p-60;
		ay *= 0x1p-60;
	} else if (ax < 0x1p-900 && ay < 0x1p-900) {
		ax *= 0x1p100;
		ay *= 0x1p100;
	}
	if (ay < ax * 0x1p-60 && !xneg) {
		v = ay / ax;
		return iec__copysign_d(v, y);
	}
	r = atan_pos(ay, ax);
	if (xneg)
		r = iec__dd_add(pi, (struct iec__dd){ -r.hi, -r.lo });
	return iec__copysign_d(r.hi + r.lo, y);
}

double iec_asin_lreal(double x)
{
	double a = iec__fabs_d(x);
	struct iec__dd c, r;

	if (iec__isnan_d(x))
		return x;
	if (a > 1)
		return IEC__NAN_D;
	if (a < 0x1p-30)
		return x;
	/* sqrt((1 - a)(1 + a)) with (1 - a) exact */
	c = iec__two_prod(1.0 - a, 1.0 + a);
	c.hi = iec__sqrt(c.hi + c.lo);
	if (c.hi == 0)
		return iec__copysign_d(PIO2.hi, x);
	r = atan_pos(a, c.hi);
	return iec__copysign_d(r.hi + r.lo, x);
}

double iec_acos_lreal(double x)
{
	static const struct iec__dd pi = { 0x1.921fb54442d18p+1,
				      0x1.1a62633145c07p-53 };
	double a = iec__fabs_d(x), s;
	struct iec__dd c, r;

	if (iec__isnan_d(x))
		return x;
	if (a > 1)
		return IEC__NAN_D;
	if (x == 1)
		return 0.0;
	if (x == -1)
		return pi.hi;
	c = iec__two_prod(1.0 - a, 1.0 + a);
	s = iec__sqrt(c.hi + c.lo);
	r = atan_pos(s, a);			/* acos(|x|) */
	if (x < 0)
		r = iec__dd_add(pi, (struct iec__dd){ -r.hi, -r.lo });
	return r.hi + r.lo;
}

/* ---------------------------------------------------------------------
 * SQRT and the REAL forms: evaluate in double, round once.
 */
double iec_sqrt_lreal(double x)
{
	if (iec__isnan_d(x))
		return x;
	if (x < 0)
		return IEC__NAN_D;
	return iec__sqrt(x);
}

float iec_sqrt_real(float x)
{
	return (float)iec_sqrt_lreal(x);
}

#define IEC__REAL_FROM_LREAL(f)						\
float iec_##f##_real(float x)						\
{									\
	return iec_lreal_to_real(iec_##f##_lreal(x));			\
}

IEC__REAL_FROM_LREAL(exp)
IEC__REAL_FROM_LREAL(ln)
IEC__REAL_FROM_LREAL(log)
IEC__REAL_FROM_LREAL(sin)
IEC__REAL_FROM_LREAL(cos)
IEC__REAL_FROM_LREAL(tan)
IEC__REAL_FROM_LREAL(asin)
IEC__REAL_FROM_LREAL(acos)
IEC__REAL_FROM_LREAL(atan)

float iec_atan2_real(float y, float x)
{
	return iec_lreal_to_real(iec_atan2_lreal(y, x));
}

float iec_expt_real(float x, float y)
{
	return iec_lreal_to_real(iec_expt_lreal(x, y));
}

float iec_expt_real_lint(float x, iec_lint n)
{
	return iec_lreal_to_real(iec_expt_lreal(x, (double)n));
}

double iec_expt_lreal_lint(double x, iec_lint n)
{
	return iec_expt_lreal(x, (double)n);
}
