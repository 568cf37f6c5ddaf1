/* ShadyLoc — BRIEF binary descriptor (Calonder, Lepetit, Strecha, Fua,
 * "BRIEF: Binary Robust Independent Elementary Features", ECCV 2010).
 *
 * 256 intensity comparisons between pixel pairs of a smoothed patch around the
 * keypoint; the pairs are drawn once from an isotropic Gaussian around the
 * centre (the paper's sampling strategy G II, sigma^2 = S^2/25) with a fixed
 * seed, so descriptors from different runs and processes compare. Written
 * here: Debian's OpenCV ships no xfeatures2d.
 */
#pragma once

#include <opencv2/core/mat.hpp>

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace shadyloc::features
{
/** 256-bit descriptor. */
struct TBriefDescriptor
{
	std::array<uint64_t, 4> w{};  //!< bit i of the descriptor is bit (i%64) of w[i/64]

	bool operator==(const TBriefDescriptor& o) const { return w == o.w; }
};

/** Bits set in x, by the classic SWAR reduction (Knuth, TAOCP 4A 7.1.3):
 * inlined, and several times faster than the library call that
 * __builtin_popcountll becomes without -mpopcnt (the build sets no global
 * target flags, so a binary runs on every x86-64). */
inline int popcount64(uint64_t x)
{
	x = x - ((x >> 1) & 0x5555555555555555ULL);
	x = (x & 0x3333333333333333ULL) + ((x >> 2) & 0x3333333333333333ULL);
	x = (x + (x >> 4)) & 0x0f0f0f0f0f0f0f0fULL;
	return static_cast<int>((x * 0x0101010101010101ULL) >> 56);
}

/** Hamming distance (number of differing bits, 0..256). */
inline int hamming(const TBriefDescriptor& a, const TBriefDescriptor& b)
{
	return popcount64(a.w[0] ^ b.w[0]) + popcount64(a.w[1] ^ b.w[1]) + popcount64(a.w[2] ^ b.w[2]) +
		   popcount64(a.w[3] ^ b.w[3]);
}

/** The 256 intensity tests of `tests` (pairs of offsets dx1, dy1, dx2, dy2)
 * about the pixel at `centre` of an image with row stride `step` [bytes]:
 * bit i is set when the first pixel of test i is darker. The caller checks
 * that every offset lies inside the image. */
template <class Tests>
void briefTests(const uint8_t* centre, ptrdiff_t step, const Tests& tests, TBriefDescriptor& d)
{
	d.w = {0, 0, 0, 0};
	for (int i = 0; i < 256; i++)
	{
		const auto& t = tests[static_cast<size_t>(i)];
		const bool bit = centre[t[1] * step + t[0]] < centre[t[3] * step + t[2]];
		d.w[i >> 6] |= static_cast<uint64_t>(bit) << (i & 63);
	}
}

class BriefExtractor
{
   public:
	/** patchSize S [px] (even, >= 8): tests lie within the SxS square around
	 * the keypoint; seed fixes the test pattern. */
	explicit BriefExtractor(int patchSize = 32, uint32_t seed = 0x5ad710c);

	/** Smoothing before the tests (the paper's 9x9 Gaussian, sigma 2); call
	 * once per image. */
	static void smooth(const cv::Mat& grey8, cv::Mat& smoothed8);

	/** Descriptor at integer pixel (x, y) of a smoothed CV_8UC1 image. False
	 * if the patch does not fit in the image (closer than radius() to a border). */
	bool compute(const cv::Mat& smoothed8, int x, int y, TBriefDescriptor& d) const;

	int radius() const { return m_radius; }	 //!< S/2 [px]
	int patchSize() const { return 2 * m_radius; }
	/** The test pattern: 256 pairs of offsets (dx1, dy1, dx2, dy2). */
	const std::vector<std::array<int8_t, 4>>& pattern() const { return m_pattern; }

   private:
	int m_radius;
	std::vector<std::array<int8_t, 4>> m_pattern;
};

}  // namespace shadyloc::features
