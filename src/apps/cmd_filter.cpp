/* shadyloc filter: derive monochrome/invariant channels in a rawlog. */
#include "Command.h"
#include "CommandLine.h"

#include <shadyloc/filters/FilterPipeline.h>


#include <iostream>

namespace cmd_filter
{
int run(int argc, char** argv)
{
	shadyloc::apps::CommandLine cli(
		"Streams a rawlog through observation filters: every object is kept and each "
		"camera observation gains derived channels (stock MRPT observations labelled "
		"<sensor>_mono, <sensor>_inv, ...).");
	auto& cmd = cli.cmd();
	TCLAP::ValueArg<std::string> in("i", "input", "input rawlog", true, "", "in.rawlog", cmd);
	TCLAP::ValueArg<std::string> out("o", "output", "output rawlog", true, "", "out.rawlog", cmd);
	TCLAP::ValueArg<std::string> cfg(
		"c", "config", "filter pipeline .ini (default: monochrome + invariant, see config/filters.ini)",
		false, "", "filters.ini", cmd);
	TCLAP::SwitchArg ext(
		"", "external-images", "write derived images as PNG in <out>_Images/", cmd);
	TCLAP::SwitchArg quiet("q", "quiet", "no progress output", cmd);
	if (const auto rc = cli.parse(argc, argv)) return *rc;

	const auto pipeline = cfg.isSet() ? shadyloc::filters::FilterPipeline::FromConfigFile(cfg.getValue())
									  : shadyloc::filters::FilterPipeline::Default();
	shadyloc::filters::RawlogFilterProcessor proc;
	proc.externalImages = ext.getValue();
	if (cfg.isSet()) proc.otherInputs.push_back(cfg.getValue());
	proc.setMinLoggingLevel(quiet.getValue() ? mrpt::system::LVL_WARN : mrpt::system::LVL_INFO);
	if (!quiet.getValue()) std::cout << "Pipeline options:\n" << pipeline.asIni() << "\n";
	proc.run(in.getValue(), out.getValue(), pipeline);
	return 0;
}
shadyloc::apps::RegisterCommand reg(
	"filter", {"derive mono/invariant channels in a rawlog (-i in -o out [-c ini])", run});
}  // namespace cmd_filter
