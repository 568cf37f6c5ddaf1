/* ShadyLoc — channel conversion for the VO. */
#include <shadyloc/filters/Filters.h>
#include <shadyloc/vo/Channel.h>

#include <stdexcept>

namespace shadyloc::vo
{
Channel parseChannel(const std::string& s)
{
	if (s == "mono" || s == "monochrome") return Channel::Mono;
	if (s == "invariant" || s == "inv") return Channel::Invariant;
	throw std::invalid_argument("unknown channel '" + s + "' (expected mono | invariant)");
}
std::string toString(Channel c) { return c == Channel::Mono ? "mono" : "invariant"; }
std::string channelSuffix(Channel c) { return c == Channel::Mono ? "_mono" : "_inv"; }

ChannelConverter::ChannelConverter(Channel c, const image::InvariantParams& p, image::ChannelOrder monoOrder)
	: m_channel(c), m_params(p), m_order(monoOrder)
{
	if (c == Channel::Invariant)
	{
		m_params.validate();
		m_inv = std::make_shared<image::InvariantTransform>(m_params);
	}
}

ChannelConverter ChannelConverter::FromConfig(
	const mrpt::config::CConfigFileBase& cfg, const std::string& channel, const std::string& invSection)
{
	const Channel c = parseChannel(channel.empty() ? cfg.read_string("vo", "channel", "mono") : channel);
	// The invariant options are exactly CFilterInvariant's: one parser, one meaning.
	CFilterInvariant f;
	if (cfg.sectionExists(invSection)) f.loadFromConfig(cfg, invSection);
	const auto order = image::parseChannelOrder(cfg.read_string("vo", "channel_order", "bgr"));
	return ChannelConverter(c, f.params(), order);
}

void ChannelConverter::convert(const cv::Mat& colour, cv::Mat& grey) const
{
	if (m_channel == Channel::Mono)
	{
		image::toMonochrome(colour, grey, m_order);
		return;
	}
	if (colour.type() != CV_8UC3)
		throw std::invalid_argument("invariant channel needs an 8-bit colour image (got a grey one?)");
	m_inv->apply(colour, grey);
}

std::string ChannelConverter::asString() const
{
	return m_channel == Channel::Mono ? "mono" : "invariant (" + m_params.asString() + ")";
}

features::TStereoFeatureOptions featureOptionsFor(
	const mrpt::config::CConfigFileBase& cfg, Channel c, const std::string& base)
{
	features::TStereoFeatureOptions o;
	o.loadFromConfigFile(cfg, base);
	const std::string s = base + "." + toString(c);
	if (cfg.sectionExists(s)) o.loadFromConfigFile(cfg, s);
	return o;
}

TStereoVOOptions voOptionsFor(const mrpt::config::CConfigFileBase& cfg, Channel c, const std::string& base)
{
	TStereoVOOptions o;
	o.loadFromConfigFile(cfg, base);
	const std::string s = base + "." + toString(c);
	if (cfg.sectionExists(s)) o.loadFromConfigFile(cfg, s);
	return o;
}

}  // namespace shadyloc::vo
