/* ShadyLoc — the VO's options for one channel. */
#include <shadyloc/vo/ChannelOptions.h>

namespace shadyloc::vo
{
features::TStereoFeatureOptions featureOptionsFor(
	const mrpt::config::CConfigFileBase& cfg, const std::string& channel, const std::string& base)
{
	features::TStereoFeatureOptions o;
	o.loadFromConfigFile(cfg, base);
	const std::string s = base + "." + channel;
	if (cfg.sectionExists(s)) o.loadFromConfigFile(cfg, s);
	return o;
}

TStereoVOOptions voOptionsFor(const mrpt::config::CConfigFileBase& cfg, const std::string& channel, const std::string& base)
{
	TStereoVOOptions o;
	o.loadFromConfigFile(cfg, base);
	const std::string s = base + "." + channel;
	if (cfg.sectionExists(s)) o.loadFromConfigFile(cfg, s);
	return o;
}

}  // namespace shadyloc::vo
