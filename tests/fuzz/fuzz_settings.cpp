/* Fuzz target: settings (.ini) text through MRPT's CConfigFileMemory into our
 * options loaders (the strict settings reader): VO, features and channel
 * options, the filter pipeline, the map's and the simulator's options. Any outcome but a crash or a sanitizer report is fine
 * (errors are exceptions with a message). */
#include "FuzzSupport.h"

#include <shadyloc/Registration.h>
#include <shadyloc/filters/FilterPipeline.h>
#include <shadyloc/sim/SimOptions.h>
#include <shadyloc/filters/Channel.h>
#include <shadyloc/map/CKeyframeMap.h>
#include <shadyloc/vo/ChannelOptions.h>
#include <shadyloc/vo/VOConfig.h>

#include <mrpt/config/CConfigFileMemory.h>

extern "C" int LLVMFuzzerInitialize(int*, char***)
{
	shadyloc::registerAllClasses();
	return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size)
{
	if (size > 64 * 1024) return 0;
	const std::string text(reinterpret_cast<const char*>(data), size);
	mrpt::config::CConfigFileMemory cfg;
	try
	{
		cfg.setContent(text);  // MRPT's own parser may refuse it (e.g. a bad $eval{})
	}
	catch (const std::exception&)
	{
		return 0;
	}
	auto attempt = [](auto&& f) {
		try
		{
			f();
		}
		catch (const std::exception&)
		{
		}
	};
	for (const char* name : {"mono", "invariant"})
		attempt([&] {
			const auto ch = shadyloc::filters::channelFromConfig(cfg, name, "fuzz.ini");
			(void)shadyloc::vo::voOptionsFor(cfg, ch.label);
			(void)shadyloc::vo::featureOptionsFor(cfg, ch.label);
		});
	attempt([&] {
		shadyloc::TKeyframeMapOptions o;
		o.loadFromConfigFile(cfg, "map");
	});
	attempt([&] { (void)shadyloc::filters::FilterPipeline::FromConfig(cfg, "fuzz.ini").asIni(); });
	attempt([&] {
		shadyloc::sim::TSimOptions o;
		o.loadFromConfigFile(cfg, "sim");
	});
	return 0;
}
