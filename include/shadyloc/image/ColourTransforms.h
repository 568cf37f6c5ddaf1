/* ShadyLoc — illumination-invariant stereo localisation on MRPT.
 *
 * Colour transforms used to derive the two image channels the localisers run
 * on: monochrome (the baseline) and illumination-invariant.
 *
 * Invariant image after McManus et al., "Shady Dealings", ICRA 2014, eq. (1)-(2),
 * which builds on Ratnasingam & McGinnity (2012) and Maddern et al. (2014):
 *
 *     I = log(R2) - alpha * log(R1) - beta * log(R3)
 *     1/l2 = alpha/l1 + beta/l3
 *
 * with R1, R2, R3 the linear sensor responses of peak wavelengths l1 < l2 < l3
 * (blue, green, red). For a narrowband sensor under Planckian illumination in
 * Wien's approximation, log(Ri) = log(I0) + log(S_i) + log(c1 l_i^-5) - c2/(T l_i):
 * the constraint on alpha and beta cancels the colour-temperature term; with
 * beta = 1 - alpha the intensity term log(I0) cancels too.
 */
#pragma once

#include <opencv2/core/mat.hpp>

#include <cstdint>
#include <iosfwd>
#include <string>
#include <utility>
#include <vector>

namespace mrpt::config
{
class CConfigFileBase;
}
namespace shadyloc::core
{
class KeyVisitor;
class SettingsSection;
class SettingsWriter;
}  // namespace shadyloc::core

namespace shadyloc::image
{
/** Memory order of the three channels of an 8-bit colour image. OpenCV and
 * mrpt::img::CImage load images as BGR. */
enum class ChannelOrder
{
	BGR,
	RGB
};

/** Where blue (R1), green (R2) and red (R3) sit in a pixel of one order. */
struct ChannelIndices
{
	int b, g, r;
};
ChannelIndices channelIndices(ChannelOrder o);

/** How encoded pixel values map back to linear sensor response before logs. */
enum class Linearisation
{
	None,  //!< values are already linear (raw sensor output)
	SRGB,  //!< IEC 61966-2-1 sRGB transfer curve (most JPEG/PNG files)
	Gamma  //!< plain power law: linear = value^gamma
};

/** What the invariant does about chroma that has less resolution than luma
 * (JPEG 4:2:0: chroma in 16x16-pixel blocks of the full image, whose block
 * edges become a grid in the invariant image, which is chroma only). */
enum class ChromaHandling
{
	None,  //!< every pixel as it comes (raw, lossless, 4:4:4)
	/** Gaussian low-pass of the colour image (chroma_sigma_px) before the
	 * logarithm: block edges become ramps FAST does not fire on. */
	Prefilter,
	/** The invariant of the 2x2-averaged image (the 4:2:0 chroma grid),
	 * upsampled back bilinearly. */
	ChromaResolution
};

ChannelOrder parseChannelOrder(const std::string& s);  //!< "rgb" | "bgr"
Linearisation parseLinearisation(const std::string& s);	 //!< "none" | "srgb" | "gamma"
std::string toString(ChannelOrder o);
std::string toString(Linearisation l);
/** The values as settings name them (core::KeyVisitor::choice). */
const std::vector<std::pair<std::string, ChannelOrder>>& channelOrderNames();
const std::vector<std::pair<std::string, Linearisation>>& linearisationNames();
const std::vector<std::pair<std::string, ChromaHandling>>& chromaHandlingNames();
std::string toString(ChromaHandling c);

/** Everything that defines the invariant image of an 8-bit colour image,
 * including its fixed quantisation to 8 bits: two images made with equal
 * parameters are comparable pixel by pixel (map vs live). */
struct InvariantParams
{
	double alpha = 0.4800;	//!< weight of log(R1) (blue); paper's Bumblebee2 value
	double beta = 0.5065;  //!< weight of log(R3) (red); paper's Bumblebee2 value
	ChannelOrder order = ChannelOrder::BGR;	 //!< channel order of the input
	Linearisation linearisation = Linearisation::None;
	double gamma = 2.2;	 //!< exponent, used when linearisation == Gamma

	/** 8-bit mapping: out = clamp(round(scale * (I + offset)), 0, 255),
	 * tails compressed as below when asked.
	 * scale in grey levels per unit of natural log; offset in log units. The
	 * default offset (see defaultOffset()) puts a neutral 18% grey surface at
	 * 0.5*scale; with scale 255 this is Maddern et al.'s "0.5 + I" mapping. */
	double scale = 255.0;
	double offset = 0.5;

	/** Tails of the 8-bit mapping, compressed (toGrey()): with g = scale *
	 * (I + offset), the output is g between knee_low and knee_high (grey
	 * levels), and runs at tail_slope_low / tail_slope_high (in (0, 1]) grey
	 * levels per level of g beyond them. Slopes of 1 (the default) leave the
	 * mapping linear, whatever the knees. Heavy-tailed scenes (saturated
	 * colours) need it: a linear mapping cannot both keep clipping under
	 * 0.5 % and give the bulk 200 grey levels there (docs/calibration.md). */
	double knee_low = 0.0, knee_high = 255.0;
	double tail_slope_low = 1.0, tail_slope_high = 1.0;

	/** Chroma subsampled input (docs/calibration.md, "Cameras that suit the
	 * invariant channel"); none keeps the image as it was before this option. */
	ChromaHandling chroma_handling = ChromaHandling::None;
	double chroma_sigma_px = 1.5;  //!< Gaussian sigma with chroma_handling = prefilter [px]

	/** Linear response given to a zero-valued pixel so logs stay finite:
	 * half of the smallest non-zero code value (in [0,1] units). */
	static constexpr double kZeroCode = 0.5;

	/** alpha, beta explicit; offset set to the default for them. */
	static InvariantParams FromAlphaBeta(double alpha, double beta);
	/** Peak wavelengths (any unit, l1 < l2 < l3); beta = 1 - alpha, so that
	 * the image is invariant to both colour temperature and intensity. */
	static InvariantParams FromWavelengths(double l1, double l2, double l3);

	/** 0.5 - (1 - alpha - beta) * log(0.18): neutral mid-grey at mid-scale. */
	double defaultOffset() const;

	/** True when a tail is compressed (a slope below 1). */
	bool hasCompressedTails() const { return tail_slope_low != 1.0 || tail_slope_high != 1.0; }
	/** The tails applied to g = scale * (I + offset). */
	double compressTails(double g) const
	{
		if (g < knee_low) return knee_low + tail_slope_low * (g - knee_low);
		if (g > knee_high) return knee_high + tail_slope_high * (g - knee_high);
		return g;
	}
	/** The 8-bit mapping of I before rounding and clamping to [0, 255]. */
	double toGrey(double I) const { return compressTails(scale * (I + offset)); }

	/** Throws std::invalid_argument naming the bad field. */
	void validate() const;

	std::string asString() const;  //!< one line, "alpha=... beta=..."
	/** Same image from the same input: every field that changes a pixel agrees
	 * (gamma only with gamma linearisation; reals within 1e-9). */
	bool sameImageAs(const InvariantParams& o) const;

	void keys(core::KeyVisitor& v);  //!< every written key, declared once (core/Options.h)
	/** Reads the keys of a section strictly (src/image/InvariantParamsSettings.cpp):
	 * alpha and beta, or peak_wavelength_{blue,green,red}_nm (then beta =
	 * 1 - alpha), channel_order, linearisation, gamma, scale and offset
	 * (absent: defaultOffset() of the new alpha, beta), knee_low, knee_high,
	 * tail_slope_low, tail_slope_high, chroma_handling, chroma_sigma_px. Absent keys keep their
	 * values; validates. Declares its keys known in `s`; the caller finishes it. */
	void readFrom(core::SettingsSection& s);
	/** Writes every key readFrom() reads back to these exact values. */
	void writeTo(core::SettingsWriter& w) const;
	/** A whole section: readFrom() and no other key; errors name file, section, key. */
	void loadFromConfigFile(const mrpt::config::CConfigFileBase& c, const std::string& section);
	/** writeTo() on a stream (no section header). */
	void dumpToTextStream(std::ostream& out) const;
};

/** Linear response in (0,1] of an 8-bit code value under a linearisation.
 * Zero maps to the linearised value of kZeroCode. */
double linearise(int code, Linearisation lin, double gamma);

/** The colour image the logarithm sees under p.chroma_handling: the input
 * itself (none), its Gaussian low-pass (prefilter), or its 2x2 average at
 * half size (chroma_resolution; chromaToInputSize() brings the invariant back). */
cv::Mat chromaInput(const cv::Mat& colour8, const InvariantParams& p);
/** An invariant made from chromaInput() back at the input's size (bilinear
 * for chroma_resolution, nothing to do otherwise). */
void chromaToInputSize(cv::Mat& invariant, const cv::Size& inputSize, const InvariantParams& p);

/** Reference (float, per-pixel std::log) invariant: CV_32F image of I in log
 * units, no offset or scale. Slow; the yardstick for tests. */
cv::Mat invariantReferenceFloat(const cv::Mat& colour8, const InvariantParams& p);

/** Reference path quantised with the same 8-bit mapping as the fast path. */
cv::Mat invariantReference8(const cv::Mat& colour8, const InvariantParams& p);

/** Naive fast-path competitor: per-pixel std::log on every pixel, 8-bit out.
 * Kept for the benchmark only. */
void invariantNaive8(const cv::Mat& colour8, cv::Mat& out8, const InvariantParams& p);

/** The fast path: three 256-entry fixed-point tables per parameter set, one
 * table look-up per channel and an integer sum per pixel. Build once, apply
 * to every frame. Thread-safe for concurrent apply() calls. */
class InvariantTransform
{
   public:
	explicit InvariantTransform(const InvariantParams& p = {});

	const InvariantParams& params() const { return m_params; }

	/** colour8: CV_8UC3 in params().order; out8 becomes CV_8UC1. */
	void apply(const cv::Mat& colour8, cv::Mat& out8) const;

	/** Both eyes of a stereo pair; the right one on a second thread when
	 * parallel is true (roughly halves the wall time on two cores). */
	void applyPair(
		const cv::Mat& left8, const cv::Mat& right8, cv::Mat& leftOut,
		cv::Mat& rightOut, bool parallel = true) const;

   private:
	InvariantParams m_params;
	// Fixed point: kFracBits fractional bits of a grey level. Table k holds
	// scale * w_k * log(lin(v)) with w = (-alpha, 1, -beta) for (R1, R2, R3);
	// the R2 table also holds scale * offset and the rounding half.
	static constexpr int kFracBits = 10;
	int32_t m_lutBlue[256], m_lutGreen[256], m_lutRed[256];
	// Compressed tails: the output of every possible sum at a quarter of a
	// grey level (a table look-up instead of per-pixel branches; within one
	// level of the reference). Index (sum >> kToneShift) - m_toneBase.
	static constexpr int kToneShift = kFracBits - 2;
	int32_t m_toneBase = 0;
	std::vector<uint8_t> m_tone;
	template <bool CompressedTails>
	void applyRows(const cv::Mat& colour8, cv::Mat& out8) const;
};

/** Monochrome (luma, ITU-R BT.601 weights) of an 8-bit colour image, 8-bit
 * out; the baseline channel. A grey input is copied. */
void toMonochrome(const cv::Mat& colour8, cv::Mat& grey8, ChannelOrder order);

/** Linearised 8-bit image (each channel through linearise(), then *255). */
void toLinear8(const cv::Mat& colour8, cv::Mat& out8, Linearisation lin, double gamma);

}  // namespace shadyloc::image
