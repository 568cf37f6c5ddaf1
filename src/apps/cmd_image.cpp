/* shadyloc image: one image file -> monochrome or invariant image file. */
#include "Command.h"
#include "CommandLine.h"

#include <shadyloc/filters/Filters.h>
#include <shadyloc/image/ColourTransforms.h>
#include <shadyloc/io/ImageFile.h>
#include <shadyloc/io/OutputTransaction.h>

#include <mrpt/config/CConfigFile.h>
#include <opencv2/imgcodecs.hpp>

#include <array>
#include <filesystem>
#include <optional>
#include <iostream>

namespace cmd_image
{
int run(int argc, char** argv)
{
	using namespace shadyloc::image;
	shadyloc::apps::CommandLine cli(
		"Transforms an image file into the monochrome or illumination-invariant channel.");
	auto& cmd = cli.cmd();
	TCLAP::UnlabeledValueArg<std::string> in("IN", "input colour image", true, "", "IN.png", cmd);
	TCLAP::UnlabeledValueArg<std::string> out("OUT", "output image (format by extension)", true, "", "OUT.png", cmd);
	std::vector<std::string> channels{"invariant", "mono"};
	TCLAP::ValuesConstraint<std::string> chanC(channels);
	TCLAP::ValueArg<std::string> channel("", "channel", "channel to compute", false, "invariant", &chanC, cmd);
	shadyloc::apps::NumberArg<double> alpha(
		cli, "", "alpha", "weight of log(blue), in [0,1] (default 0.48, the paper's Bumblebee2)", 0.48, "a", 0.0, 1.0);
	shadyloc::apps::NumberArg<double> beta(cli, "", "beta", "weight of log(red), in [0,1.5] (default 0.5065)", 0.5065, "b", 0.0, 1.5);
	TCLAP::ValueArg<std::string> wl(
		"", "wavelengths", "peak wavelengths blue,green,red in nm; sets alpha and beta = 1 - alpha (instead of --alpha/--beta)",
		false, "", "l1,l2,l3", cmd);
	std::vector<std::string> lins{"none", "srgb", "gamma"};
	TCLAP::ValuesConstraint<std::string> linC(lins);
	TCLAP::ValueArg<std::string> lin("", "linearise", "none|srgb|gamma (before the logs)", false, "none", &linC, cmd);
	shadyloc::apps::NumberArg<double> gamma(cli, "", "gamma", "exponent for --linearise gamma, in (0,10)", 2.2, "g", 1e-6, 10.0);
	shadyloc::apps::NumberArg<double> scale(cli, "", "scale", "grey levels per unit log response (> 0)", 255.0, "s", 1e-9);
	TCLAP::ValueArg<std::string> config(
		"c", "config",
		"the invariant transform of a CFilterInvariant section of this .ini (e.g. calibrate-alpha's OUT.ini, with "
		"its calibrated mapping) instead of --alpha/--beta/--wavelengths/--linearise/--gamma/--scale",
		false, "", "ini", cmd);
	TCLAP::ValueArg<std::string> section("", "section", "the section of --config", false, "invariant", "name", cmd);
	if (const auto rc = cli.parse(argc, argv)) return *rc;
	if (config.isSet() &&
		(alpha.isSet() || beta.isSet() || wl.isSet() || lin.isSet() || gamma.isSet() || scale.isSet()))
		return cli.usageError(
			"--config gives the whole transform: drop --alpha/--beta/--wavelengths/--linearise/--gamma/--scale");
	if (section.isSet() && !config.isSet()) return cli.usageError("--section needs --config");
	if (wl.isSet() && (alpha.isSet() || beta.isSet()))
		return cli.usageError("--wavelengths sets alpha and beta: give either --wavelengths or --alpha/--beta");
	if (gamma.isSet() && lin.getValue() != "gamma")
		return cli.usageError("--gamma is used only with --linearise gamma");
	std::optional<std::array<double, 3>> peaks;
	if (wl.isSet())
	{
		std::vector<std::string> parts;
		std::string cur;
		for (char c : wl.getValue() + ",")
			if (c == ',') parts.push_back(cur), cur.clear();
			else cur += c;
		if (parts.size() != 3)
			return cli.usageError(
				"--wavelengths: expected three values blue,green,red, got " + std::to_string(parts.size()) + " ('" +
				wl.getValue() + "')");
		std::array<double, 3> l{};
		for (int i = 0; i < 3; i++)
		{
			try
			{
				l[i] = shadyloc::apps::parseNumber<double>(parts[i]);
			}
			catch (const std::invalid_argument& e)
			{
				return cli.usageError(std::string("--wavelengths: ") + e.what());
			}
		}
		peaks = l;
	}

	shadyloc::io::OutputTransaction outputs;
	outputs.addInput(in.getValue(), "input image");
	const std::string outTmp = outputs.addFile(out.getValue(), "output image");
	shadyloc::io::checkImageWritable(out.getValue());
	cv::Mat img;
	try
	{
		img = shadyloc::io::readImageFile(in.getValue());
	}
	catch (const shadyloc::io::ImageFileError& e)
	{
		throw std::runtime_error(std::string("cannot read image ") + e.what());
	}
	if (img.depth() != CV_8U)
		throw std::runtime_error("'" + in.getValue() + "': only 8-bit images are supported");

	cv::Mat result;
	if (channel.getValue() == "mono")
		toMonochrome(img, result, ChannelOrder::BGR);
	else
	{
		if (img.channels() != 3)
			throw std::runtime_error(
				"'" + in.getValue() + "': the invariant channel needs a colour image, this one has " +
				std::to_string(img.channels()) + " channel(s)");
		InvariantParams p;
		if (config.isSet())
		{
			if (!std::filesystem::is_regular_file(config.getValue()))
				throw std::runtime_error("--config '" + config.getValue() + "': no such file");
			const mrpt::config::CConfigFile cfg(config.getValue());
			if (!cfg.sectionExists(section.getValue()))
				throw std::runtime_error(
					"--config '" + config.getValue() + "': no section [" + section.getValue() + "]");
			shadyloc::CFilterInvariant f;
			f.loadFromConfig(cfg, section.getValue());	// strict: unknown keys name file, section and key
			p = f.params();
		}
		else if (peaks)
		{
			try
			{
				p = InvariantParams::FromWavelengths((*peaks)[0], (*peaks)[1], (*peaks)[2]);
			}
			catch (const std::invalid_argument& e)
			{
				return cli.usageError(std::string("--wavelengths: ") + e.what());
			}
		}
		else
			p = InvariantParams::FromAlphaBeta(alpha.getValue(), beta.getValue());
		if (!config.isSet())
		{
			p.linearisation = parseLinearisation(lin.getValue());
			p.gamma = gamma.getValue();
			p.scale = scale.getValue();
		}
		p.validate();
		std::cout << "invariant: " << p.asString() << "\n";
		InvariantTransform(p).apply(img, result);
	}
	bool written = false;
	try
	{
		written = cv::imwrite(outTmp, result);
	}
	catch (const cv::Exception& e)
	{
		throw std::runtime_error("'" + out.getValue() + "': cannot write image: " + e.err);
	}
	if (!written) throw std::runtime_error("'" + out.getValue() + "': cannot write image");
	outputs.commit();
	return 0;
}
shadyloc::apps::RegisterCommand reg("image", {"one image file -> mono or invariant image file", run});
}  // namespace cmd_image
