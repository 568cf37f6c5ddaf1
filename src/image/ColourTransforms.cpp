/* ShadyLoc — colour transforms (see header for the method and citations). */
#include <shadyloc/image/ColourTransforms.h>

#include <shadyloc/core/Options.h>

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <future>
#include <sstream>
#include <stdexcept>

namespace shadyloc::image
{
namespace
{
std::string lower(std::string s)
{
	std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return std::tolower(c); });
	return s;
}

void requireColour8(const cv::Mat& m, const char* what)
{
	if (m.empty()) throw std::invalid_argument(std::string(what) + ": empty image");
	if (m.type() != CV_8UC3)
		throw std::invalid_argument(
			std::string(what) + ": expected an 8-bit 3-channel colour image, got " +
			std::to_string(m.channels()) + " channel(s), depth " + std::to_string(m.depth()));
}
}  // namespace

ChannelIndices channelIndices(ChannelOrder o)
{
	return o == ChannelOrder::BGR ? ChannelIndices{0, 1, 2} : ChannelIndices{2, 1, 0};
}

ChannelOrder parseChannelOrder(const std::string& s)
{
	const auto l = lower(s);
	if (l == "bgr") return ChannelOrder::BGR;
	if (l == "rgb") return ChannelOrder::RGB;
	throw std::invalid_argument("channel order must be 'rgb' or 'bgr', got '" + s + "'");
}

Linearisation parseLinearisation(const std::string& s)
{
	const auto l = lower(s);
	if (l == "none" || l.empty()) return Linearisation::None;
	if (l == "srgb") return Linearisation::SRGB;
	if (l == "gamma") return Linearisation::Gamma;
	throw std::invalid_argument("linearisation must be 'none', 'srgb' or 'gamma', got '" + s + "'");
}

std::string toString(ChromaHandling c)
{
	for (const auto& [name, value] : chromaHandlingNames())
		if (value == c) return name;
	return "?";
}

std::string toString(ChannelOrder o) { return o == ChannelOrder::BGR ? "bgr" : "rgb"; }
std::string toString(Linearisation l)
{
	switch (l)
	{
		case Linearisation::None: return "none";
		case Linearisation::SRGB: return "srgb";
		case Linearisation::Gamma: return "gamma";
	}
	return "?";
}

InvariantParams InvariantParams::FromAlphaBeta(double alpha, double beta)
{
	InvariantParams p;
	p.alpha = alpha;
	p.beta = beta;
	p.offset = p.defaultOffset();
	return p;
}

InvariantParams InvariantParams::FromWavelengths(double l1, double l2, double l3)
{
	if (!(l1 > 0 && l1 < l2 && l2 < l3))
		throw std::invalid_argument(
			"peak wavelengths must satisfy 0 < l1 < l2 < l3 (blue < green < red)");
	// 1/l2 = alpha/l1 + (1-alpha)/l3  =>  alpha = (1/l2 - 1/l3) / (1/l1 - 1/l3)
	const double alpha = (1.0 / l2 - 1.0 / l3) / (1.0 / l1 - 1.0 / l3);
	return FromAlphaBeta(alpha, 1.0 - alpha);
}

double InvariantParams::defaultOffset() const
{
	return 0.5 - (1.0 - alpha - beta) * std::log(0.18);
}

void InvariantParams::validate() const
{
	core::checkKeys(*this);	 // the ranges, declared with the keys (InvariantParamsSettings.cpp)
	if (!(knee_high > knee_low)) throw std::invalid_argument("knee_high: must be above knee_low");
	if (linearisation == Linearisation::Gamma && !(gamma > 0 && gamma < 10))
		throw std::invalid_argument("gamma: must be in (0, 10) with linearisation = gamma");
}

std::string InvariantParams::asString() const
{
	std::ostringstream s;
	s.precision(8);
	s << "alpha=" << alpha << " beta=" << beta << " order=" << toString(order)
	  << " linearisation=" << toString(linearisation);
	if (linearisation == Linearisation::Gamma) s << " gamma=" << gamma;
	s << " scale=" << scale << " offset=" << offset;
	if (chroma_handling != ChromaHandling::None) s << " chroma_handling=" << toString(chroma_handling);
	if (chroma_handling == ChromaHandling::Prefilter) s << " chroma_sigma_px=" << chroma_sigma_px;
	if (hasCompressedTails())
		s << " knee_low=" << knee_low << " knee_high=" << knee_high << " tail_slope_low=" << tail_slope_low
		  << " tail_slope_high=" << tail_slope_high;
	return s.str();
}

bool InvariantParams::sameImageAs(const InvariantParams& o) const
{
	const auto eq = [](double a, double b) { return std::abs(a - b) <= 1e-9; };
	return eq(alpha, o.alpha) && eq(beta, o.beta) && order == o.order && linearisation == o.linearisation &&
		   (linearisation != Linearisation::Gamma || eq(gamma, o.gamma)) && eq(scale, o.scale) &&
		   eq(offset, o.offset) && chroma_handling == o.chroma_handling &&
		   (chroma_handling != ChromaHandling::Prefilter || eq(chroma_sigma_px, o.chroma_sigma_px)) &&
		   hasCompressedTails() == o.hasCompressedTails() &&
		   (!hasCompressedTails() || (eq(knee_low, o.knee_low) && eq(knee_high, o.knee_high) &&
									  eq(tail_slope_low, o.tail_slope_low) && eq(tail_slope_high, o.tail_slope_high)));
}

double linearise(int code, Linearisation lin, double gamma)
{
	const double v = (code <= 0 ? InvariantParams::kZeroCode : double(code)) / 255.0;
	switch (lin)
	{
		case Linearisation::None: return v;
		case Linearisation::SRGB:
			return v <= 0.04045 ? v / 12.92 : std::pow((v + 0.055) / 1.055, 2.4);
		case Linearisation::Gamma: return std::pow(v, gamma);
	}
	return v;
}

cv::Mat chromaInput(const cv::Mat& colour8, const InvariantParams& p)
{
	cv::Mat out;
	switch (p.chroma_handling)
	{
		case ChromaHandling::None: return colour8;
		case ChromaHandling::Prefilter: cv::GaussianBlur(colour8, out, cv::Size(), p.chroma_sigma_px); return out;
		case ChromaHandling::ChromaResolution:
			// INTER_AREA at exactly half is the 2x2 mean: one value per 4:2:0 chroma sample.
			cv::resize(colour8, out, cv::Size((colour8.cols + 1) / 2, (colour8.rows + 1) / 2), 0, 0, cv::INTER_AREA);
			return out;
	}
	return colour8;
}

void chromaToInputSize(cv::Mat& invariant, const cv::Size& inputSize, const InvariantParams& p)
{
	if (p.chroma_handling != ChromaHandling::ChromaResolution) return;
	cv::Mat full;
	cv::resize(invariant, full, inputSize, 0, 0, cv::INTER_LINEAR);
	invariant = full;
}

namespace
{
/** The reference float invariant of the image the logarithm sees
 * (chromaInput()): half size with chroma_resolution. */
cv::Mat referenceFloatOfChromaInput(const cv::Mat& colour8In, const InvariantParams& p)
{
	requireColour8(colour8In, "invariant (reference)");
	p.validate();
	const cv::Mat colour8 = chromaInput(colour8In, p);
	const auto ci = channelIndices(p.order);
	cv::Mat out(colour8.size(), CV_32F);
	for (int y = 0; y < colour8.rows; y++)
	{
		const auto* in = colour8.ptr<cv::Vec3b>(y);
		auto* o = out.ptr<float>(y);
		for (int x = 0; x < colour8.cols; x++)
		{
			const double r1 = linearise(in[x][ci.b], p.linearisation, p.gamma);
			const double r2 = linearise(in[x][ci.g], p.linearisation, p.gamma);
			const double r3 = linearise(in[x][ci.r], p.linearisation, p.gamma);
			o[x] = float(std::log(r2) - p.alpha * std::log(r1) - p.beta * std::log(r3));
		}
	}
	return out;
}
}  // namespace

cv::Mat invariantReferenceFloat(const cv::Mat& colour8, const InvariantParams& p)
{
	cv::Mat out = referenceFloatOfChromaInput(colour8, p);
	chromaToInputSize(out, colour8.size(), p);
	return out;
}

cv::Mat invariantReference8(const cv::Mat& colour8, const InvariantParams& p)
{
	const cv::Mat f = referenceFloatOfChromaInput(colour8, p);
	cv::Mat out(f.size(), CV_8U);
	for (int y = 0; y < f.rows; y++)
	{
		const auto* in = f.ptr<float>(y);
		auto* o = out.ptr<uint8_t>(y);
		for (int x = 0; x < f.cols; x++)
			o[x] = cv::saturate_cast<uint8_t>(std::lround(p.toGrey(double(in[x]))));
	}
	// Upsampled after the 8-bit mapping, as the fast path does: interpolating
	// values beyond [0, 255] before clamping would make other images.
	chromaToInputSize(out, colour8.size(), p);
	return out;
}

void invariantNaive8(const cv::Mat& colour8, cv::Mat& out8, const InvariantParams& p)
{
	requireColour8(colour8, "invariant (naive)");
	const auto ci = channelIndices(p.order);
	out8.create(colour8.size(), CV_8U);
	const float a = float(p.alpha), b = float(p.beta);
	const float zero = float(InvariantParams::kZeroCode);
	for (int y = 0; y < colour8.rows; y++)
	{
		const auto* in = colour8.ptr<cv::Vec3b>(y);
		auto* o = out8.ptr<uint8_t>(y);
		for (int x = 0; x < colour8.cols; x++)
		{
			// Linear input assumed, as the common naive implementation does.
			const float r1 = std::max<float>(in[x][ci.b], zero) / 255.f;
			const float r2 = std::max<float>(in[x][ci.g], zero) / 255.f;
			const float r3 = std::max<float>(in[x][ci.r], zero) / 255.f;
			const float I = std::log(r2) - a * std::log(r1) - b * std::log(r3);
			o[x] = cv::saturate_cast<uint8_t>(p.toGrey(I));
		}
	}
}

InvariantTransform::InvariantTransform(const InvariantParams& p) : m_params(p)
{
	m_params.validate();
	const double unit = double(1 << kFracBits);
	for (int v = 0; v < 256; v++)
	{
		const double logv = std::log(linearise(v, p.linearisation, p.gamma));
		m_lutBlue[v] = int32_t(std::lround(-unit * p.scale * p.alpha * logv));
		m_lutRed[v] = int32_t(std::lround(-unit * p.scale * p.beta * logv));
		// Offset and the rounding half folded into one table; the sum is then
		// shifted right (floor), which equals round-half-up of the true value.
		m_lutGreen[v] = int32_t(std::lround(unit * (p.scale * (logv + p.offset) + 0.5)));
	}
	if (!p.hasCompressedTails()) return;
	// Every sum the three tables can make, at quarter levels: the sum is
	// (g + 0.5) in fixed point, so a bin's g is its start minus the half.
	const auto lo = [](const int32_t* t) { return *std::min_element(t, t + 256); };
	const auto hi = [](const int32_t* t) { return *std::max_element(t, t + 256); };
	const int32_t sumMin = lo(m_lutBlue) + lo(m_lutGreen) + lo(m_lutRed);
	const int32_t sumMax = hi(m_lutBlue) + hi(m_lutGreen) + hi(m_lutRed);
	m_toneBase = sumMin >> kToneShift;
	m_tone.resize(size_t((sumMax >> kToneShift) - m_toneBase + 1));
	const double binLevels = double(1 << kToneShift) / unit;
	for (size_t i = 0; i < m_tone.size(); i++)
	{
		const double g = double(m_toneBase + int32_t(i)) * binLevels - 0.5 + 0.5 * binLevels;	 // bin centre
		m_tone[i] = cv::saturate_cast<uint8_t>(std::lround(p.compressTails(g)));
	}
}

template <bool CompressedTails>
void InvariantTransform::applyRows(const cv::Mat& colour8, cv::Mat& out8) const
{
	const auto ci = channelIndices(m_params.order);
	const int cols = colour8.cols;
	for (int y = 0; y < colour8.rows; y++)
	{
		const uint8_t* in = colour8.ptr<uint8_t>(y);
		uint8_t* o = out8.ptr<uint8_t>(y);
		for (int x = 0; x < cols; x++)
		{
			const uint8_t* px = in + 3 * x;
			const int32_t sum = m_lutBlue[px[ci.b]] + m_lutGreen[px[ci.g]] + m_lutRed[px[ci.r]];
			if constexpr (CompressedTails)
				o[x] = m_tone[size_t((sum >> kToneShift) - m_toneBase)];
			else
			{
				const int32_t v = sum >> kFracBits;
				o[x] = uint8_t(v < 0 ? 0 : (v > 255 ? 255 : v));
			}
		}
	}
}

void InvariantTransform::apply(const cv::Mat& colour8In, cv::Mat& out8) const
{
	requireColour8(colour8In, "invariant");
	const cv::Mat colour8 = chromaInput(colour8In, m_params);
	out8.create(colour8.size(), CV_8U);
	// The linear mapping keeps the plain loop (the common case, and the benchmarked one).
	if (m_params.hasCompressedTails())
		applyRows<true>(colour8, out8);
	else
		applyRows<false>(colour8, out8);
	chromaToInputSize(out8, colour8In.size(), m_params);
}

void InvariantTransform::applyPair(
	const cv::Mat& left8, const cv::Mat& right8, cv::Mat& leftOut, cv::Mat& rightOut,
	bool parallel) const
{
	if (!parallel)
	{
		apply(left8, leftOut);
		apply(right8, rightOut);
		return;
	}
	auto right = std::async(std::launch::async, [&] { apply(right8, rightOut); });
	apply(left8, leftOut);
	right.get();  // rethrows the right eye's exception, if any
}

void toMonochrome(const cv::Mat& colour8, cv::Mat& grey8, ChannelOrder order)
{
	if (colour8.empty()) throw std::invalid_argument("monochrome: empty image");
	if (colour8.type() == CV_8UC1)
	{
		colour8.copyTo(grey8);
		return;
	}
	requireColour8(colour8, "monochrome");
	cv::cvtColor(
		colour8, grey8, order == ChannelOrder::BGR ? cv::COLOR_BGR2GRAY : cv::COLOR_RGB2GRAY);
}

void toLinear8(const cv::Mat& colour8, cv::Mat& out8, Linearisation lin, double gamma)
{
	requireColour8(colour8, "linearise");
	cv::Mat lut(1, 256, CV_8U);
	for (int v = 0; v < 256; v++)
		lut.at<uint8_t>(v) = v == 0 ? 0 : cv::saturate_cast<uint8_t>(255.0 * linearise(v, lin, gamma));
	cv::LUT(colour8, lut, out8);
}

}  // namespace shadyloc::image
