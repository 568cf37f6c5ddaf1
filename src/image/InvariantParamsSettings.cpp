/* ShadyLoc — InvariantParams read from and written to settings. One parser
 * for every place that names an invariant transform: the CFilterInvariant
 * section of a filter config, the [invariant] section of a VO config. */
#include <shadyloc/core/Settings.h>
#include <shadyloc/image/ColourTransforms.h>

#include <ostream>

namespace shadyloc::image
{
namespace
{
const std::vector<std::pair<std::string, ChannelOrder>> kOrders = {
	{"bgr", ChannelOrder::BGR}, {"rgb", ChannelOrder::RGB}};
const std::vector<std::pair<std::string, Linearisation>> kLinearisations = {
	{"none", Linearisation::None}, {"srgb", Linearisation::SRGB}, {"gamma", Linearisation::Gamma}};
}  // namespace

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
	else
	{
		s.read("alpha", p.alpha);
		s.read("beta", p.beta);
	}
	s.readChoice("channel_order", p.order, kOrders);
	s.readChoice("linearisation", p.linearisation, kLinearisations);
	s.read("gamma", p.gamma);
	s.read("scale", p.scale);
	p.offset = p.defaultOffset();
	s.read("offset", p.offset);
	s.read("knee_low", p.knee_low);
	s.read("knee_high", p.knee_high);
	s.read("tail_slope_low", p.tail_slope_low);
	s.read("tail_slope_high", p.tail_slope_high);
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

void InvariantParams::writeTo(core::SettingsWriter& w) const
{
	w.value("alpha", alpha, "I = log(R2) - alpha log(R1) - beta log(R3): weights of log(blue) and log(red)");
	w.value("beta", beta);
	w.value("channel_order", toString(order), "memory order of the colour input: bgr | rgb");
	w.value("linearisation", toString(linearisation), "none | srgb | gamma");
	w.value("gamma", gamma, "exponent with linearisation = gamma");
	w.value("scale", scale, "8-bit mapping clamp(round(scale (I + offset))): grey levels per unit log response");
	w.value("offset", offset, "[log units]");
	w.value(
		"knee_low", knee_low,
		"compressed tails: g = scale (I + offset) is kept between the knees [grey levels], beyond them it runs at "
		"the tail slopes (1 = linear mapping)");
	w.value("knee_high", knee_high);
	w.value("tail_slope_low", tail_slope_low);
	w.value("tail_slope_high", tail_slope_high);
}

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
