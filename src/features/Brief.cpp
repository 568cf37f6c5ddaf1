/* ShadyLoc — BRIEF descriptor (Calonder et al., ECCV 2010). */
#include <shadyloc/features/Brief.h>

#include <opencv2/imgproc.hpp>

#include <cmath>
#include <random>
#include <stdexcept>
#include <string>

namespace shadyloc::features
{
BriefExtractor::BriefExtractor(int patchSize, uint32_t seed)
{
	if (patchSize < 8 || patchSize > 250 || patchSize % 2)
		throw std::invalid_argument(
			"BRIEF patch size must be even and in [8, 250], got " + std::to_string(patchSize));
	m_radius = patchSize / 2;
	// Strategy G II of the paper: (X, Y) i.i.d. Gaussian(0, S^2/25), clipped
	// to the patch. std::mt19937 is specified bit-exactly by the standard, and
	// the Gaussian is made here by Box-Muller (std::normal_distribution is not
	// portable across standard libraries), so the pattern is the same everywhere.
	std::mt19937 rng(seed);
	const double sigma = patchSize / 5.0;
	auto uniform = [&rng]() { return (rng() + 0.5) / 4294967296.0; };
	auto gauss = [&]() {
		const double u1 = uniform(), u2 = uniform();
		return sigma * std::sqrt(-2.0 * std::log(u1)) * std::cos(2 * M_PI * u2);
	};
	auto coord = [&]() {
		const long v = std::lround(gauss());
		return static_cast<int8_t>(std::max<long>(-m_radius + 1, std::min<long>(m_radius - 1, v)));
	};
	m_pattern.resize(256);
	for (auto& t : m_pattern)
	{
		do
		{
			t = {coord(), coord(), coord(), coord()};
		} while (t[0] == t[2] && t[1] == t[3]);	 // a pixel compared with itself says nothing
	}
}

void BriefExtractor::smooth(const cv::Mat& grey8, cv::Mat& smoothed8)
{
	cv::GaussianBlur(grey8, smoothed8, cv::Size(9, 9), 2.0, 2.0, cv::BORDER_REFLECT_101);
}

bool BriefExtractor::compute(const cv::Mat& img, int x, int y, TBriefDescriptor& d) const
{
	if (x < m_radius || y < m_radius || x >= img.cols - m_radius || y >= img.rows - m_radius)
		return false;
	briefTests(img.ptr<uint8_t>(y) + x, static_cast<ptrdiff_t>(img.step[0]), m_pattern, d);
	return true;
}

}  // namespace shadyloc::features
