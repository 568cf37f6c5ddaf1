/* ShadyLoc — a diagnostic of a simulated survey's map against the scene's
 * true geometry. For every STEP-th keyframe that carries ground truth it
 * renders the scene's depth from the keyframe's true left-camera pose and
 * compares each channel's landmarks with it: a landmark is a gross error when its
 * stored depth P.z is further than max(3 sigma_z, 5 %) from the true depth
 * at its pixel, and no pixel of the 3x3 neighbourhood is closer (a corner on
 * a silhouette may legitimately take either side's depth).
 *
 *   landmark_depth_probe MAP SIM.ini STEP [ORACLE_MAP]
 *
 * With ORACLE_MAP it also writes a copy of the map whose last channel's
 * landmarks are moved along their rays to the true depth (uR from it), every
 * other keyframe and landmark as they were: localising against it separates
 * the error of the map's depths from the live frames' (docs/localisation.md,
 * "Where the invariant solves' error comes from").
 *
 * Prints one CSV row per probed keyframe (landmarks and gross errors per
 * channel, their median relative depth error), then per channel the totals
 * and the quantiles of the disparity error (PROBE_VERBOSE=1: each gross
 * error). A diagnostic for developers: not part of the test suite. */
#include <shadyloc/Registration.h>
#include <shadyloc/io/Trajectory.h>
#include <shadyloc/map/CKeyframeMap.h>
#include <shadyloc/sim/StereoSimulator.h>

#include <mrpt/poses/CPose3D.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <vector>

using namespace shadyloc;

namespace
{
/** Relative error of the depth nearest z among the 3x3 true depths; < 0 when
 * the pixel sees only sky. */
double nearestRelativeError(const cv::Mat& depth, float u, float v, double z)
{
	const int x0 = static_cast<int>(std::lround(u)), y0 = static_cast<int>(std::lround(v));
	double best = -1;
	for (int y = y0 - 1; y <= y0 + 1; y++)
		for (int x = x0 - 1; x <= x0 + 1; x++)
		{
			if (x < 0 || y < 0 || x >= depth.cols || y >= depth.rows) continue;
			const float d = depth.at<float>(y, x);
			if (d <= 0) continue;
			const double e = std::abs(z - d) / d;
			if (best < 0 || e < best) best = e;
		}
	return best;
}

/** Whether the true depth varies by less than 5 % over the 7x7 window
 * around the pixel (no depth edge under the stereo patch). */
bool interior(const cv::Mat& depth, float u, float v)
{
	const int x0 = static_cast<int>(std::lround(u)), y0 = static_cast<int>(std::lround(v));
	float lo = 1e9f, hi = 0;
	for (int y = y0 - 3; y <= y0 + 3; y++)
		for (int x = x0 - 3; x <= x0 + 3; x++)
		{
			if (x < 0 || y < 0 || x >= depth.cols || y >= depth.rows) return false;
			const float d = depth.at<float>(y, x);
			if (d <= 0) return false;
			lo = std::min(lo, d);
			hi = std::max(hi, d);
		}
	return hi - lo < 0.05f * lo;
}

/** kf with channel c's landmarks moved along their rays to the true depth. */
map::TMapKeyframe atTrueDepth(map::TMapKeyframe kf, size_t c, const cv::Mat& depth)
{
	for (auto& m : kf.channels[c])
	{
		const float d = depth.at<float>(static_cast<int>(std::lround(m.v)), static_cast<int>(std::lround(m.uL)));
		if (d <= 0) continue;
		const double fxb = m.P.z() * (m.uL - m.uR);	 // the map stores (uL, v, uR)
		m.uR = static_cast<float>(m.uL - fxb / d);
		m.P *= d / m.P.z();
	}
	return kf;
}

/** A channel's tallies over the probed keyframes. */
struct TChannelStats
{
	long n = 0, wrong = 0, sky = 0;
	std::vector<double> disparityError, disparityErrorInterior;	 //!< [px], positive = too close
	/** Disparity errors over their stated sigma: landmarks refined by
	 * re-observations (sigma_d), and the pair's own (sqrt 2 sigma_px). */
	std::vector<double> normalisedRefined, normalisedPair;
	std::vector<double> refinedError, refinedSigma;	//!< [px]
};

int px(float u) { return static_cast<int>(std::lround(u)); }

/** Compares one keyframe's landmarks of one channel with the true depth;
 * returns the median relative error of its gross errors (0 if none). */
double probeLandmarks(
	const map::TMapKeyframe& kf, size_t c, double sigma_px, const sim::TRenderAux& aux, TChannelStats& st)
{
	std::vector<double> grossRel;
	for (const auto& m : kf.channels[c])
	{
		st.n++;
		const double e = nearestRelativeError(aux.depth, m.uL, m.v, m.P.z());
		if (e < 0)
		{
			st.sky++;
			continue;
		}
		const float dTrue = aux.depth.at<float>(px(m.v), px(m.uL));
		if (dTrue > 0 && e < 0.3)
		{
			const double fxb = m.P.z() * (m.uL - m.uR);	 // fx * b, as the landmark was triangulated
			const double de = (m.uL - m.uR) - fxb / dTrue;
			st.disparityError.push_back(de);
			if (m.sigma_d > 0)
			{
				st.normalisedRefined.push_back(de / m.sigma_d);
				st.refinedError.push_back(de);
				st.refinedSigma.push_back(m.sigma_d);
			}
			else
				st.normalisedPair.push_back(de / (std::sqrt(2.0) * sigma_px));
			if (interior(aux.depth, m.uL, m.v)) st.disparityErrorInterior.push_back(de);
		}
		if (e * m.P.z() <= 3 * std::sqrt(std::max(0.0, m.cov(2, 2))) || e <= 0.05) continue;
		st.wrong++;
		grossRel.push_back(e);
		if (std::getenv("PROBE_VERBOSE"))
			std::fprintf(stderr, "gross: kf %u channel %zu uL %.1f v %.1f uR %.1f z %.2f true %.2f zncc %.3f material %d\n",
				kf.id, c, m.uL, m.v, m.uR, m.P.z(), dTrue, m.zncc, aux.material.at<uint8_t>(px(m.v), px(m.uL)));
	}
	if (grossRel.empty()) return 0;
	std::nth_element(grossRel.begin(), grossRel.begin() + grossRel.size() / 2, grossRel.end());
	return grossRel[grossRel.size() / 2];
}

void printQuantiles(const std::string& what, std::vector<double> d)
{
	if (d.empty()) return;
	std::sort(d.begin(), d.end());
	const auto q = [&](double f) { return d[static_cast<size_t>(f * (d.size() - 1))]; };
	std::fprintf(stderr, "%s (%zu landmarks within 30 %% of the true depth) [px]: p10 %.3f p25 %.3f median %.3f p75 %.3f p90 %.3f\n",
		what.c_str(), d.size(), q(0.1), q(0.25), q(0.5), q(0.75), q(0.9));
}
/** Mean squared normalised error (NEES, 1 dof) and the share within 3 sigma. */
void printNormalised(const std::string& what, const std::vector<double>& e)
{
	if (e.empty()) return;
	double ss = 0;
	size_t in3 = 0;
	for (double x : e)
	{
		ss += x * x;
		in3 += std::abs(x) <= 3;
	}
	std::vector<double> a;
	for (double x : e) a.push_back(std::abs(x));
	std::sort(a.begin(), a.end());
	std::fprintf(stderr, "%s: %zu landmarks, disparity error / sigma: mean square %.2f, median |.| %.2f, within 3 sigma %.1f %%\n",
		what.c_str(), e.size(), ss / e.size(), a[a.size() / 2], 100.0 * in3 / e.size());
}
}  // namespace

int main(int argc, char** argv)
{
	if (argc != 4 && argc != 5)
	{
		std::cerr << "usage: landmark_depth_probe MAP SIM.ini STEP [ORACLE_MAP]\n";
		return 2;
	}
	registerAllClasses();
	const auto mapPtr = CKeyframeMap::LoadFromFile(argv[1]);
	const CKeyframeMap& map = *mapPtr;
	sim::StereoSimulator simulator(sim::TSimOptions::FromFile(argv[2]));
	const int step = std::max(1, std::atoi(argv[3]));
	const size_t nch = map.channels().size();
	CKeyframeMap oracle;
	oracle.options = map.options;
	oracle.setup(map.calibration(), map.imageWidth(), map.imageHeight(), map.channels());
	for (const auto& r : map.runs()) oracle.addRun(r);
	std::vector<TChannelStats> stats(nch);

	std::printf("keyframe");
	for (const auto& c : map.channels()) std::printf(",%s_n,%s_gross,%s_gross_median_rel", c.label.c_str(), c.label.c_str(), c.label.c_str());
	std::printf("\n");
	for (const auto& kf : map.keyframes())
	{
		if (kf.id % step != 0 || !kf.T_gt_kf)
		{
			oracle.appendKeyframe(kf);
			continue;
		}
		cv::Mat left, right;
		sim::TRenderAux aux;
		simulator.renderLinear(io::toCPose3D(*kf.T_gt_kf), left, right, &aux);
		std::printf("%u", kf.id);
		for (size_t c = 0; c < nch; c++)
		{
			const long n0 = stats[c].n, w0 = stats[c].wrong;
			const double med = probeLandmarks(kf, c, map.channels()[c].sigma_px, aux, stats[c]);
			std::printf(",%ld,%ld,%.3f", stats[c].n - n0, stats[c].wrong - w0, med);
		}
		std::printf("\n");
		std::fflush(stdout);
		oracle.appendKeyframe(atTrueDepth(kf, nch - 1, aux.depth));
	}
	if (argc == 5) oracle.saveToFile(argv[4]);
	for (size_t c = 0; c < nch; c++)
	{
		const auto& st = stats[c];
		const std::string& label = map.channels()[c].label;
		std::fprintf(stderr, "%s: %ld landmarks, %ld gross depth errors (%.2f %%), %ld on sky\n", label.c_str(), st.n,
			st.wrong, st.n ? 100.0 * st.wrong / st.n : 0.0, st.sky);
		printQuantiles(label + " disparity error", st.disparityError);
		printQuantiles(label + " disparity error, no depth edge in the 7x7 window", st.disparityErrorInterior);
		printNormalised(label + " refined by re-observations", st.normalisedRefined);
		printQuantiles(label + " disparity error of the refined ones", st.refinedError);
		printQuantiles(label + " sigma of the refined ones", st.refinedSigma);
		printNormalised(label + " the pair's own", st.normalisedPair);
	}
	return 0;
}
