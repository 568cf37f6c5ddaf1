/* ShadyLoc — the degree and the stage timer, one home for each (they were
 * defined in every file that needed them). */
#pragma once

#include <chrono>
#include <cmath>

namespace shadyloc::core
{
/** Radians per degree: x_deg * kDeg is in radians, x_rad / kDeg in degrees. */
constexpr double kDeg = M_PI / 180.0;

/** Milliseconds on the steady clock since t0 (the stages' timings). */
inline double msSince(std::chrono::steady_clock::time_point t0)
{
	return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

/** Runs f and adds its time to acc [ms]. */
template <class F>
void timed(double& acc, F&& f)
{
	const auto t0 = std::chrono::steady_clock::now();
	f();
	acc += msSince(t0);
}

}  // namespace shadyloc::core
