/* ShadyLoc — InvariantParams read from and written to settings. One parser
 * for every place that names an invariant transform: the CFilterInvariant
 * section of a filter config, the [invariant] section of a VO config. */
#include <shadyloc/core/Options.h>
#include <shadyloc/image/ColourTransforms.h>

#include <ostream>

namespace shadyloc::image
{
const std::vector<std::pair<std::string, ChannelOrder>>& channelOrderNames()
{
	static const std::vector<std::pair<std::string, ChannelOrder>> names = {
		{"bgr", ChannelOrder::BGR}, {"rgb", ChannelOrder::RGB}};
	return names;
}
const std::vector<std::pair<std::string, Linearisation>>& linearisationNames()
{
	static const std::vector<std::pair<std::string, Linearisation>> names = {
		{"none", Linearisation::None}, {"srgb", Linearisation::SRGB}, {"gamma", Linearisation::Gamma}};
	return names;
}

const std::vector<std::pair<std::string, ChromaHandling>>& chromaHandlingNames()
{
	static const std::vector<std::pair<std::string, ChromaHandling>> names = {
		{"none", ChromaHandling::None},
		{"prefilter", ChromaHandling::Prefilter},
		{"chroma_resolution", ChromaHandling::ChromaResolution}};
	return names;
}

void InvariantParams::readFrom(core::SettingsSection& s)
{
	InvariantParams p = *this;
	// Either three peak wavelengths (beta = 1 - alpha), or alpha and beta.
	const char* wl[3] = {"peak_wavelength_blue_nm", "peak_wavelength_green_nm", "peak_wavelength_red_nm"};
	int given = 0;
	for (const char* k : wl) given += s.has(k) ? 1 : 0;
	const bool hasAlphaBeta = s.has("alpha") || s.has("beta");
	if (given > 0)
	{
		if (hasAlphaBeta) s.fail("alpha", "give either peak_wavelength_*_nm or alpha/beta, not both");
		if (given < 3) s.fail(wl[0], "give all three peak_wavelength_*_nm, or alpha and beta");
		double l[3] = {0, 0, 0};
		for (int i = 0; i < 3; i++) s.read(wl[i], l[i]);
		try
		{
			const auto w = InvariantParams::FromWavelengths(l[0], l[1], l[2]);
			p.alpha = w.alpha;
			p.beta = w.beta;
		}
		catch (const std::invalid_argument& e)
		{
			s.fail(wl[0], e.what());
		}
	}
	core::readKeys(s, p);
	if (!s.has("offset")) p.offset = p.defaultOffset();  // the default for the new alpha, beta
	try
	{
		p.validate();
	}
	catch (const std::invalid_argument& e)
	{
		throw core::SettingsError(s.where() + " " + e.what());
	}
	*this = p;
}

void InvariantParams::keys(core::KeyVisitor& v)
{
	using core::Range;
	v("alpha", alpha, "", Range::closed(0, 1), "I = log(R2) - alpha log(R1) - beta log(R3): weights of log(blue) and log(red)");
	v("beta", beta, "", Range::closed(0, 1.5), "");
	v.choice("channel_order", order, channelOrderNames(), "memory order of the colour input: bgr | rgb");
	v.choice("linearisation", linearisation, linearisationNames(), "none | srgb | gamma");
	v("gamma", gamma, "", Range::any(), "exponent with linearisation = gamma");
	// The upper bound keeps the fixed-point sums of InvariantTransform in 32 bits.
	v("scale", scale, "", Range::openClosed(0, 10000),
	  "8-bit mapping clamp(round(scale (I + offset))): grey levels per unit log response");
	// |I| stays under ~20 log units for 8-bit input; the bound keeps the sums in 32 bits too.
	v("offset", offset, "log units", Range::closed(-100, 100), "");
	v("knee_low", knee_low, "", Range::closed(0, 255),
	  "compressed tails: g = scale (I + offset) is kept between the knees [grey levels], beyond them it runs at "
	  "the tail slopes (1 = linear mapping)");
	v("knee_high", knee_high, "", Range::closed(0, 255), "");
	v("tail_slope_low", tail_slope_low, "", Range::openClosed(0, 1), "");
	v("tail_slope_high", tail_slope_high, "", Range::openClosed(0, 1), "");
	v.choice(
		"chroma_handling", chroma_handling, chromaHandlingNames(),
		"chroma subsampled input (JPEG 4:2:0): none | prefilter (Gaussian low-pass before the log) | "
		"chroma_resolution (the invariant of the 2x2 mean, upsampled)");
	// Above 8 px the low-pass takes more texture than the 16-px block grid it is for.
	v("chroma_sigma_px", chroma_sigma_px, "px", Range::openClosed(0, 8), "Gaussian sigma with chroma_handling = prefilter");
}

void InvariantParams::writeTo(core::SettingsWriter& w) const { core::writeKeys(w, *this); }

void InvariantParams::loadFromConfigFile(const mrpt::config::CConfigFileBase& c, const std::string& section)
{
	core::SettingsSection s(c, section);
	readFrom(s);
	s.finish();
}

void InvariantParams::dumpToTextStream(std::ostream& out) const
{
	core::SettingsWriter w(out);
	writeTo(w);
}

}  // namespace shadyloc::image
