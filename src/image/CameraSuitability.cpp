/* ShadyLoc — the checks behind calibrate-alpha's suitability verdict (see
 * the header and docs/calibration.md). */
#include <shadyloc/image/CameraSuitability.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <sstream>

namespace shadyloc::image
{
namespace
{
constexpr int kGridPeriod = 16;
constexpr double kMaxStep = 0.5;  // log units: a step clamped here counts as an edge, whatever its height

std::string fmt(double v, int prec)
{
	std::ostringstream s;
	s << std::fixed << std::setprecision(prec) << v;
	return s.str();
}

/** Mean clamped |step| of I across each line of an image: lines[q] is the
 * line between columns (or rows) q-1 and q, for q in [1, size). */
std::vector<double> lineSteps(const cv::Mat& I, bool columns)
{
	const int n = columns ? I.cols : I.rows, along = columns ? I.rows : I.cols;
	std::vector<double> lines(size_t(n), 0.0);
	for (int y = 0; y < I.rows; y++)
	{
		const float* row = I.ptr<float>(y);
		const float* above = y > 0 ? I.ptr<float>(y - 1) : nullptr;
		for (int x = 0; x < I.cols; x++)
		{
			if (columns && x > 0) lines[size_t(x)] += std::min(double(std::abs(row[x] - row[x - 1])), kMaxStep);
			if (!columns && above) lines[size_t(y)] += std::min(double(std::abs(row[x] - above[x])), kMaxStep);
		}
	}
	for (auto& l : lines) l /= along;
	return lines;
}

/** For every line at phase `phase` (mod 16) with 7 lines on each side: its
 * step over the mean step of the lines around it (within 8,
 * none at a multiple of 8). Per line, so that a scene edge that happens to
 * lie on the grid moves one ratio, not the figure: JPEG blocks raise them all. */
void addLineRatios(const std::vector<double>& lines, int phase, std::vector<double>& ratios)
{
	// Line 0 is the image's edge: the first line of the phase is the one at 8 or 16.
	for (size_t at = size_t(phase > 0 ? phase : kGridPeriod); at + 8 <= lines.size(); at += kGridPeriod)
	{
		double around = 0;
		int n = 0;
		for (size_t k = at - 7; k <= at + 7; k++)
			if (k % 8 != 0) around += lines[k], n++;
		around /= n;
		if (around > 1e-6) ratios.push_back(lines[at] / around);
	}
}

double median(std::vector<double> v)
{
	if (v.empty()) return 1.0;
	std::nth_element(v.begin(), v.begin() + long(v.size() / 2), v.end());
	return v[v.size() / 2];
}

/** The float invariant I of an 8-bit colour image through one log table per code. */
cv::Mat invariantOf(const cv::Mat& colour8, const InvariantParams& p, const std::array<float, 256>& L)
{
	const int b = p.order == ChannelOrder::BGR ? 0 : 2, r = 2 - b;
	cv::Mat I(colour8.size(), CV_32F);
	for (int y = 0; y < colour8.rows; y++)
	{
		const uint8_t* px = colour8.ptr<uint8_t>(y);
		float* o = I.ptr<float>(y);
		for (int x = 0; x < colour8.cols; x++, px += 3)
			o[x] = L[px[1]] - float(p.alpha) * L[px[b]] - float(p.beta) * L[px[r]];
	}
	return I;
}

/** Severity of a measured value against two limits. */
Suitability against(double v, double doubtful, double unsuitable)
{
	if (v >= unsuitable) return Suitability::Unsuitable;
	if (v >= doubtful) return Suitability::Doubtful;
	return Suitability::Suitable;
}

bool atSearchBound(const TAlphaCurve& c, const TAlphaSearch& s)
{
	// Within one grid step (or the refinement window) of a bound, the
	// minimum may lie beyond it: the interval then says nothing.
	const double margin = std::max(s.step, s.refineHalfWidth);
	return c.best <= s.alphaMin + margin || c.best >= s.alphaMax - margin || c.ciLow <= s.alphaMin + 1e-9 ||
		   c.ciHigh >= s.alphaMax - 1e-9;
}

void judgeGrid(const TSuitabilityEvidence& e, const TSuitabilityLimits& l, TSuitabilityVerdict& v)
{
	if (!e.gridMeasured) return;
	const double g = std::max(e.grid.ratio16, e.grid.ratio8);
	v.checks.push_back(
		"block grid in the invariant: the step across a 16-px line is x" + fmt(e.grid.ratio16, 2) +
		" the steps around it, across an 8-px line x" + fmt(e.grid.ratio8, 2) + " (medians over the lines; 1 = none; " +
		"doubtful from " + fmt(l.gridDoubtful, 2) + ", unsuitable from " + fmt(l.gridUnsuitable, 2) + ")");
	const auto sev = against(g, l.gridDoubtful, l.gridUnsuitable);
	if (sev != Suitability::Suitable)
		v.add(
			"block-grid", sev,
			"the invariant shows a JPEG block grid (steps across its lines x" + fmt(g, 2) +
				" those around them): features pile up on it; use lossless or raw images (chroma_handling = prefilter "
				"removes the grid, not the loss)");
}

void judgeSubsampling(const TSuitabilityEvidence& e, TSuitabilityVerdict& v)
{
	if (e.jpegFiles == 0) return;
	v.checks.push_back(
		"JPEG files: " + std::to_string(e.jpegFiles) + ", with subsampled chroma: " +
		std::to_string(e.subsampledFiles.size()));
	if (e.subsampledFiles.empty()) return;
	v.add(
		"chroma-subsampled", Suitability::Doubtful,
		std::to_string(e.subsampledFiles.size()) + " of " + std::to_string(e.jpegFiles) +
			" JPEG files have subsampled chroma (first: " + e.subsampledFiles.front() +
			"): the invariant, which is chroma only, has less resolution than the image");
}

void judgeClipping(const TSuitabilityEvidence& e, const TSuitabilityLimits& l, TSuitabilityVerdict& v)
{
	v.checks.push_back("saturated pixels: " + fmt(100 * e.saturated, 1) + " %");
	const auto sev = against(e.saturated, l.clippedDoubtful, l.clippedUnsuitable);
	if (sev != Suitability::Suitable)
		v.add(
			"clipping", sev,
			fmt(100 * e.saturated, 1) +
				" % of the pixels have a saturated channel: their ratios, and so the invariant, are wrong there");
}

void judgeToneCurve(const TSuitabilityEvidence& e, const TSuitabilityLimits& l, TSuitabilityVerdict& v)
{
	if (e.tone.size() < 2)
	{
		v.checks.push_back("tone curve: not measurable from these data (needs shadow pairs)");
		return;
	}
	const auto &stated = e.tone[0], &other = e.tone[1];
	v.checks.push_back(
		"tone curve: shadow ratio drifts with brightness by " + fmt(stated.drift, 3) + " under the stated '" +
		stated.curve + "', " + fmt(other.drift, 3) + " under '" + other.curve + "' (" + std::to_string(stated.items) +
		" pair-channels)");
	if (stated.drift >= l.toneDriftFloor && stated.drift > l.toneDriftRatio * other.drift)
		v.add(
			"tone-curve", Suitability::Doubtful,
			"the data follow the '" + other.curve + "' curve better than the stated '" + stated.curve +
				"' (drift " + fmt(other.drift, 3) + " against " + fmt(stated.drift, 3) + "): check --linearise");
}

void judgeEstimates(const TSuitabilityEvidence& e, const TSuitabilityLimits& l, TSuitabilityVerdict& v)
{
	std::vector<const TAlphaCurve*> trusted;
	for (const auto& c : e.curves)
	{
		if (c.method == "entropy") continue;  // see the header
		trusted.push_back(&c);
		if (!atSearchBound(c, e.search)) continue;
		v.add(
			"at-search-bound", c.method == e.chosenMethod ? Suitability::Unsuitable : Suitability::Doubtful,
			c.method + " estimate " + fmt(c.best, 3) + " (interval [" + fmt(c.ciLow, 3) + ", " + fmt(c.ciHigh, 3) +
				"]) at the search bound [" + fmt(e.search.alphaMin, 2) + ", " + fmt(e.search.alphaMax, 2) +
				"]: the data do not follow the model, the interval means nothing");
	}
	if (trusted.size() < 2)
	{
		if (!e.curves.empty()) v.checks.push_back("methods compared: only one method (besides entropy) had data");
		return;
	}
	const auto [lo, hi] = std::minmax_element(
		trusted.begin(), trusted.end(), [](const TAlphaCurve* a, const TAlphaCurve* b) { return a->best < b->best; });
	const double apart = (*hi)->best - (*lo)->best;
	v.checks.push_back("methods compared: estimates within " + fmt(apart, 3) + " (entropy left out)");
	if (apart > l.methodsApart)
		v.add(
			"methods-disagree", Suitability::Doubtful,
			(*lo)->method + " says " + fmt((*lo)->best, 3) + ", " + (*hi)->method + " " + fmt((*hi)->best, 3) +
				": further apart than " + fmt(l.methodsApart, 2));
}
}  // namespace

TBlockGrid blockGridOf(const std::vector<cv::Mat>& images, const InvariantParams& p)
{
	p.validate();
	std::array<float, 256> L{};
	for (int v = 0; v < 256; v++) L[size_t(v)] = float(std::log(linearise(v, p.linearisation, p.gamma)));
	std::vector<double> at16, at8;
	for (const auto& img : images)
	{
		if (img.type() != CV_8UC3) throw std::invalid_argument("block grid: needs 8-bit colour images");
		cv::Mat I = invariantOf(chromaInput(img, p), p, L);
		chromaToInputSize(I, img.size(), p);
		for (const bool columns : {true, false})
		{
			const auto lines = lineSteps(I, columns);
			addLineRatios(lines, 0, at16);
			addLineRatios(lines, 8, at8);
		}
	}
	return {median(at16), median(at8)};
}

double saturatedShare(const std::vector<cv::Mat>& images, const TCalibrationInput& in)
{
	double saturated = 0, total = 0;
	for (const auto& img : images)
	{
		if (img.type() != CV_8UC3) throw std::invalid_argument("saturation: needs 8-bit colour images");
		for (int y = int(in.skipTopFraction * img.rows); y < img.rows; y++)
		{
			const uint8_t* px = img.ptr<uint8_t>(y);
			for (int x = 0; x < img.cols; x++, px += 3)
				saturated += (px[0] >= in.maxCode || px[1] >= in.maxCode || px[2] >= in.maxCode) ? 1 : 0;
			total += img.cols;
		}
	}
	return total > 0 ? saturated / total : 0;
}

std::string jpegChromaSubsampling(const std::string& path)
{
	std::ifstream f(path, std::ios::binary);
	auto byte = [&f]() { return f.get(); };
	if (byte() != 0xFF || byte() != 0xD8) return "";
	// Segments up to the frame header: FF, marker, 2-byte length (itself included).
	while (f)
	{
		int marker = byte();
		if (marker != 0xFF) return "";
		while (marker == 0xFF) marker = byte();
		const int high = byte();  // two reads in sequence: the operands of | are not
		const int len = (high << 8) | byte();
		if (!f || len < 2) return "";
		if (marker == 0xC0 || marker == 0xC1 || marker == 0xC2)
		{
			f.ignore(5);  // precision, height, width
			const int components = byte();
			if (components != 3) return "other";
			std::array<int, 3> h{}, v{};
			for (int c = 0; c < 3; c++)
			{
				byte();	 // component id
				const int hv = byte();
				h[size_t(c)] = hv >> 4, v[size_t(c)] = hv & 15;
				byte();	 // quantisation table
			}
			if (!f || h[1] != h[2] || v[1] != v[2]) return f ? "other" : "";
			if (h[0] == h[1] && v[0] == v[1]) return "4:4:4";
			if (h[0] == 2 * h[1] && v[0] == 2 * v[1]) return "4:2:0";
			if (h[0] == 2 * h[1] && v[0] == v[1]) return "4:2:2";
			return "other";
		}
		f.ignore(len - 2);
	}
	return "";
}

namespace
{
/** |slope| of log(free) - log(shadow) against their mean, per channel of
 * one pair, over the mask; NaN with fewer than 100 pixels. */
std::array<double, 3> driftsOfPair(const TShadowPair& p, const cv::Mat& mask, const std::array<float, 256>& L)
{
	std::array<double, 3> out{};
	for (int c = 0; c < 3; c++)
	{
		double n = 0, sumT = 0, sumD = 0, sumTT = 0, sumTD = 0;
		for (int y = 0; y < mask.rows; y++)
		{
			const uint8_t* m = mask.ptr<uint8_t>(y);
			const uint8_t* f = p.free.ptr<uint8_t>(y);
			const uint8_t* s = p.shadow.ptr<uint8_t>(y);
			for (int x = 0; x < mask.cols; x++)
			{
				if (!m[x]) continue;
				// The mean, not log(free): noise in free would enter both sides and bias the slope.
				const double lf = L[f[3 * x + c]], ls = L[s[3 * x + c]], t = 0.5 * (lf + ls), d = lf - ls;
				n++, sumT += t, sumD += d, sumTT += t * t, sumTD += t * d;
			}
		}
		if (n < 100)
		{
			out[size_t(c)] = std::nan("");
			continue;
		}
		const double var = sumTT / n - (sumT / n) * (sumT / n), cov = sumTD / n - (sumT / n) * (sumD / n);
		out[size_t(c)] = var > 1e-12 ? std::abs(cov / var) : std::nan("");
	}
	return out;
}
}  // namespace

std::vector<TToneCurveDrift> toneCurveDrifts(const std::vector<TShadowPair>& pairs, const TCalibrationInput& in)
{
	in.validate();
	std::vector<cv::Mat> masks;	 // one mask, the stated curve's, for every curve tried
	for (const auto& p : pairs) masks.push_back(shadowMask(p, in));
	std::vector<TToneCurveDrift> out;
	const bool statedSrgb = in.linearisation == Linearisation::SRGB;
	for (const bool srgb : {statedSrgb, !statedSrgb})
	{
		std::array<float, 256> L{};
		for (int v = 0; v < 256; v++)
			L[size_t(v)] = float(std::log(linearise(v, srgb ? Linearisation::SRGB : Linearisation::None, 1.0)));
		std::vector<double> drifts;
		for (size_t i = 0; i < pairs.size(); i++)
			for (const double d : driftsOfPair(pairs[i], masks[i], L))
				if (!std::isnan(d)) drifts.push_back(d);
		TToneCurveDrift t;
		t.curve = srgb ? "srgb" : (in.linearisation == Linearisation::Gamma ? "gamma" : "none");
		t.items = int(drifts.size());
		if (!drifts.empty())
		{
			std::nth_element(drifts.begin(), drifts.begin() + long(drifts.size() / 2), drifts.end());
			t.drift = drifts[drifts.size() / 2];
		}
		out.push_back(t);
		if (drifts.empty()) return {};	// no usable mask: not measurable
	}
	return out;
}

std::string toString(Suitability s)
{
	switch (s)
	{
		case Suitability::Suitable: return "suitable";
		case Suitability::Doubtful: return "doubtful";
		case Suitability::Unsuitable: return "unsuitable";
	}
	return "?";
}

void TSuitabilityVerdict::add(const std::string& code, Suitability severity, const std::string& text)
{
	reasons.push_back({code, severity, text});
	verdict = std::max(verdict, severity);
}

int TSuitabilityVerdict::exitCode() const
{
	switch (verdict)
	{
		case Suitability::Suitable: return 0;
		case Suitability::Doubtful: return 3;
		case Suitability::Unsuitable: return 4;
	}
	return 4;
}

TSuitabilityVerdict judgeSuitability(const TSuitabilityEvidence& e, const TSuitabilityLimits& l)
{
	TSuitabilityVerdict v;
	judgeGrid(e, l, v);
	judgeSubsampling(e, v);
	judgeClipping(e, l, v);
	judgeToneCurve(e, l, v);
	judgeEstimates(e, l, v);
	return v;
}

}  // namespace shadyloc::image
