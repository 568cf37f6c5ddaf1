/* ShadyLoc — image channels as filter objects. */
#include <shadyloc/filters/Channel.h>
#include <shadyloc/io/StereoFrameSource.h>

#include <mrpt/config/CConfigFileMemory.h>
#include <mrpt/obs/CObservationStereoImages.h>

#include <stdexcept>

namespace shadyloc::filters
{
bool TChannel::isNamed(const std::string& name) const
{
	if (name.empty()) return false;
	if (name == label) return true;
	const std::string& s = suffix();
	return !s.empty() && (s == name || (s[0] == '_' && s.compare(1, std::string::npos, name) == 0));
}

void TChannel::convertPair(const cv::Mat& l, const cv::Mat& r, cv::Mat& lo, cv::Mat& ro) const
{
	std::vector<cv::Mat> out;
	filter->transformImages({l, r}, out);
	lo = out.at(0);
	ro = out.at(1);
}

std::string TChannel::asString() const
{
	const std::string d = filter->describe();
	return label + " (" + filter->GetRuntimeClass()->className + ", suffix " + suffix() +
		   (d.empty() ? "" : ": " + d) + ")";
}

std::vector<TChannel> channelsOf(const FilterPipeline& p)
{
	std::vector<TChannel> out;
	for (size_t i = 0; i < p.filters.size(); i++) out.push_back({p.label(i), p.filters[i]});
	return out;
}

namespace
{
std::string namesOf(const std::vector<TChannel>& chs)
{
	std::string s;
	for (const auto& c : chs) s += (s.empty() ? "" : ", ") + c.label + " (" + c.suffix() + ")";
	return s;
}
}  // namespace

TChannel defaultChannel(const std::string& name)
{
	const auto defaults = channelsOf(FilterPipeline::Default());
	for (const auto& c : defaults)
		if (c.isNamed(name)) return c;
	throw std::invalid_argument("unknown channel '" + name + "' (built-in channels: " + namesOf(defaults) + ")");
}

TChannel channelFromConfig(
	const mrpt::config::CConfigFileBase& cfg, const std::string& name, const std::string& what)
{
	if (name.empty()) throw std::invalid_argument("'" + what + "': empty channel name");
	// 1. The config's own pipeline, when it has one.
	std::vector<TChannel> fromPipeline;
	if (cfg.sectionExists(kPipelineSection) && !cfg.read_string(kPipelineSection, "pipeline", "").empty())
	{
		fromPipeline = channelsOf(FilterPipeline::FromConfig(cfg, what));
		for (const auto& c : fromPipeline)
			if (c.isNamed(name)) return c;
	}
	// 2. A section of that name ("inv" finds the built-in's [invariant]).
	const auto defaults = channelsOf(FilterPipeline::Default());
	const TChannel* builtin = nullptr;
	for (const auto& c : defaults)
		if (c.isNamed(name)) builtin = &c;
	const std::string sect = cfg.sectionExists(name) || !builtin ? name : builtin->label;
	if (cfg.sectionExists(sect))
	{
		if (!cfg.read_string(sect, "class", "").empty())
			return {sect, FilterPipeline::FromSections(cfg, {sect}, what).filters.at(0)};
		if (!builtin)
			throw std::invalid_argument(
				"'" + what + "': [" + sect + "] class: missing (a channel section names its filter class, "
				"e.g. class = CFilterInvariant)");
		// A built-in channel's section may leave the class out: it configures the built-in filter.
		auto f = std::dynamic_pointer_cast<CObservationFilter>(
			mrpt::rtti::classFactory(builtin->filter->GetRuntimeClass()->className));
		try
		{
			f->loadFromConfig(cfg, sect);
		}
		catch (const std::exception& e)
		{
			throw std::invalid_argument("'" + what + "': " + e.what());
		}
		return {sect, f};
	}
	// 3. The built-in channel.
	if (builtin) return *builtin;
	throw std::invalid_argument(
		"'" + what + "': unknown channel '" + name + "' (no filter section or suffix of that name; " +
		(fromPipeline.empty() ? std::string() : "the config's pipeline has " + namesOf(fromPipeline) + "; ") +
		"built-in channels: " + namesOf(defaults) + ")");
}

TChannelInput resolveChannelInput(const std::string& rawlog, const TChannel& channel, const std::string& cameraLabel)
{
	TChannelInput in;
	in.rawlog = rawlog;
	const std::string rec = readPipelineRecord(rawlog);
	std::vector<std::string> derived = {channel.suffix()};
	if (!rec.empty())
	{
		in.hasRecord = true;
		mrpt::config::CConfigFileMemory cfg(rec);
		const auto recorded = FilterPipeline::FromConfig(cfg, rawlog + " (filter record)");
		for (const auto& f : recorded.filters)
		{
			derived.push_back(f->common.output_suffix);
			if (f->common.output_suffix == channel.suffix() && !in.recorded) in.recorded = f;
		}
	}
	in.derivedSuffixes = derived;
	in.sensorLabel = io::findStereoLabel(rawlog, io::labelWithSuffix(channel.suffix(), cameraLabel));
	in.filtered = !in.sensorLabel.empty();
	if (!in.filtered)
	{
		in.recorded.reset();
		in.sensorLabel = cameraLabel;
	}
	return in;
}

}  // namespace shadyloc::filters
