/* ShadyLoc — a binomial proportion's exact interval and the binomial CDF
 * behind it: the bounds of a false-fix share and of the probability that a
 * blind episode reaches a distance (Evaluation.h, the leave-one-out merge). */
#pragma once

#include <cstddef>

namespace shadyloc::eval
{
/** The exact (Clopper-Pearson) two-sided interval of a binomial proportion:
 * k successes in n trials, confidence `confidence` (0.95: 95 %). The bounds
 * solve P(X >= k | p_lo) = alpha/2 and P(X <= k | p_hi) = alpha/2 with
 * alpha = 1 - confidence (C. J. Clopper, E. S. Pearson, "The use of confidence
 * or fiducial limits illustrated in the case of the binomial", Biometrika 26,
 * 1934); for k = 0 the lower bound is 0 and the upper 1 - (alpha/2)^(1/n), for
 * k = n the reverse. The interval covers the true p at least `confidence` of
 * the time for every p (conservative), and unlike a bootstrap it does not
 * collapse to [0, 0] when no trial succeeds. n = 0 gives [0, 1]. Throws
 * std::invalid_argument when k > n or confidence is not in (0, 1). */
struct TProportionInterval
{
	double lo = 0, hi = 1;	//!< [0..1]
};
TProportionInterval clopperPearson(size_t k, size_t n, double confidence = 0.95);

/** P(X <= k) for X ~ Binomial(n, p), summed in log space over the shorter
 * tail (accurate to ~1e-15 absolute; p in [0, 1]). */
double binomialCdf(size_t k, size_t n, double p);

}  // namespace shadyloc::eval
