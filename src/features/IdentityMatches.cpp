/* ShadyLoc — features found again at the same place (see the header). */
#include <shadyloc/features/Brief.h>
#include <shadyloc/features/IdentityMatches.h>
#include <shadyloc/features/StereoFeatures.h>

#include <opencv2/imgproc.hpp>

#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>

namespace shadyloc::features
{
namespace
{
struct TDescribed
{
	std::vector<cv::Point2f> points;
	std::vector<TBriefDescriptor> desc;
};

TDescribed describe(const cv::Mat& grey8, const TIdentityMatchOptions& o, const BriefExtractor& brief)
{
	cv::Mat img = grey8;
	if (o.presmoothSigma > 0) cv::GaussianBlur(grey8, img, cv::Size(), o.presmoothSigma);
	std::vector<cv::KeyPoint> kp;
	detectFastGrid(img, o.fastThreshold, o.gridCols, o.gridRows, o.perCell, brief.radius() + 1, kp);
	cv::Mat smoothed;
	BriefExtractor::smooth(img, smoothed);
	TDescribed d;
	for (const auto& k : kp)
	{
		TBriefDescriptor desc;
		if (!brief.compute(smoothed, int(k.pt.x), int(k.pt.y), desc)) continue;
		d.points.push_back(k.pt);
		d.desc.push_back(desc);
	}
	return d;
}

/** Distance of pixel coordinate v to the nearest block line (lines lie
 * between pixels period*k - 1 and period*k) [px, from 0.5]. */
double toGridLine(double v, int period)
{
	const double phase = std::fmod(v + 0.5, double(period));
	return std::min(phase, period - phase);
}

bool onGrid(const cv::Point2f& p, int period, int band)
{
	return toGridLine(p.x, period) < band || toGridLine(p.y, period) < band;
}
}  // namespace

double gridPileUp(double coordsNearGrid, double coordsOffGrid, const TIdentityMatchOptions& o)
{
	if (o.gridBand <= 0 || 2 * o.gridBand >= o.gridPeriod) throw std::invalid_argument("grid pile-up: need 0 < 2 band < period");
	// Per unit length: the band covers 2 band of every period pixels.
	const double nearShare = 2.0 * o.gridBand / o.gridPeriod;
	if (coordsOffGrid <= 0) return coordsNearGrid > 0 ? std::numeric_limits<double>::infinity() : 1.0;
	return (coordsNearGrid / nearShare) / (coordsOffGrid / (1.0 - nearShare));
}

TIdentityMatches identityMatches(const cv::Mat& a, const cv::Mat& b, const TIdentityMatchOptions& o)
{
	if (a.type() != CV_8UC1 || b.type() != CV_8UC1 || a.size() != b.size())
		throw std::invalid_argument("identity matches: need two 8-bit grey images of one size");
	const BriefExtractor brief;
	const TDescribed da = describe(a, o, brief), db = describe(b, o, brief);
	TIdentityMatches m;
	m.keypoints = int(da.points.size());
	for (const auto& p : da.points)
		for (const double v : {double(p.x), double(p.y)}) (toGridLine(v, o.gridPeriod) < o.gridBand ? m.coordsNearGrid : m.coordsOffGrid)++;
	for (size_t i = 0; i < da.desc.size(); i++)
	{
		int best = 257, second = 257;
		size_t bestJ = 0;
		for (size_t j = 0; j < db.desc.size(); j++)
		{
			const int h = hamming(da.desc[i], db.desc[j]);
			if (h < best) second = best, best = h, bestJ = j;
			else if (h < second) second = h;
		}
		if (best > 256 || !(best < o.ratio * second)) continue;
		m.matches++;
		if (cv::norm(da.points[i] + o.shift - db.points[bestJ]) > o.maxOffsetPx) continue;
		m.correct++;
		m.correctOffGrid += onGrid(da.points[i], o.gridPeriod, o.gridBand) ? 0 : 1;
	}
	return m;
}

}  // namespace shadyloc::features
