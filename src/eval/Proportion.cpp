/* ShadyLoc — exact binomial intervals (Proportion.h). */
#include <shadyloc/eval/Proportion.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace shadyloc::eval
{
namespace
{
/** log P(X = i), X ~ Binomial(n, p), 0 < p < 1. */
double logBinomialPmf(size_t i, size_t n, double p)
{
	const double N = static_cast<double>(n), I = static_cast<double>(i);
	return std::lgamma(N + 1) - std::lgamma(I + 1) - std::lgamma(N - I + 1) + I * std::log(p) + (N - I) * std::log1p(-p);
}

/** log sum_{i = a..b} P(X = i), by log-sum-exp (the terms span hundreds of
 * orders of magnitude for large n). */
double logBinomialRange(size_t a, size_t b, size_t n, double p)
{
	double mx = -std::numeric_limits<double>::infinity();
	for (size_t i = a; i <= b; i++) mx = std::max(mx, logBinomialPmf(i, n, p));
	if (!std::isfinite(mx)) return mx;
	double s = 0;
	for (size_t i = a; i <= b; i++) s += std::exp(logBinomialPmf(i, n, p) - mx);
	return mx + std::log(s);
}

/** The p in (0, 1) where the decreasing function f(p) = P(X <= k | p)
 * equals `target`, by bisection (f is continuous and strictly decreasing in
 * p for k < n; 200 halvings reach the double's resolution). */
double solveCdf(size_t k, size_t n, double target)
{
	double a = 0, b = 1;
	for (int it = 0; it < 200 && b - a > 1e-15; it++)
	{
		const double m = 0.5 * (a + b);
		if (binomialCdf(k, n, m) > target)
			a = m;
		else
			b = m;
	}
	return 0.5 * (a + b);
}
}  // namespace

double binomialCdf(size_t k, size_t n, double p)
{
	if (!(p >= 0 && p <= 1)) throw std::invalid_argument("binomialCdf: p = " + std::to_string(p) + " is not in [0, 1]");
	if (k >= n) return 1.0;
	if (p == 0) return 1.0;
	if (p == 1) return 0.0;
	// The shorter tail, so that few terms are summed and no 1 - x cancels
	// where the sum is small.
	if (k < n - k) return std::min(1.0, std::exp(logBinomialRange(0, k, n, p)));
	return std::max(0.0, 1.0 - std::exp(logBinomialRange(k + 1, n, n, p)));
}

TProportionInterval clopperPearson(size_t k, size_t n, double confidence)
{
	if (k > n)
		throw std::invalid_argument(
			"clopperPearson: " + std::to_string(k) + " successes in " + std::to_string(n) + " trials");
	if (!(confidence > 0 && confidence < 1))
		throw std::invalid_argument("clopperPearson: confidence " + std::to_string(confidence) + " is not in (0, 1)");
	TProportionInterval r;
	if (n == 0) return r;  // no trial: no information
	const double half = 0.5 * (1 - confidence);
	const double N = static_cast<double>(n);
	// Lower: P(X >= k | lo) = alpha/2, i.e. P(X <= k-1 | lo) = 1 - alpha/2.
	r.lo = k == 0 ? 0.0 : (k == n ? std::pow(half, 1 / N) : solveCdf(k - 1, n, 1 - half));
	// Upper: P(X <= k | hi) = alpha/2.
	r.hi = k == n ? 1.0 : (k == 0 ? 1 - std::pow(half, 1 / N) : solveCdf(k, n, half));
	return r;
}

}  // namespace shadyloc::eval
