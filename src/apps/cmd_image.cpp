/* shadyloc image: one image file -> monochrome or invariant image file. */
#include "Command.h"

#include <shadyloc/image/ColourTransforms.h>
#include <shadyloc/io/AtomicFile.h>

#include <mrpt/3rdparty/tclap/CmdLine.h>

#include <opencv2/imgcodecs.hpp>

#include <filesystem>
#include <iostream>

namespace
{
int run(int argc, char** argv)
{
	using namespace shadyloc::image;
	TCLAP::CmdLine cmd("Transforms an image file into the monochrome or illumination-invariant channel.", ' ', "0.1");
	TCLAP::UnlabeledValueArg<std::string> in("IN", "input colour image", true, "", "IN.png", cmd);
	TCLAP::UnlabeledValueArg<std::string> out("OUT", "output image (format by extension)", true, "", "OUT.png", cmd);
	std::vector<std::string> channels{"invariant", "mono"};
	TCLAP::ValuesConstraint<std::string> chanC(channels);
	TCLAP::ValueArg<std::string> channel("", "channel", "channel to compute", false, "invariant", &chanC, cmd);
	TCLAP::ValueArg<double> alpha("", "alpha", "weight of log(blue) (default 0.48, the paper's Bumblebee2)", false, 0.48, "a", cmd);
	TCLAP::ValueArg<double> beta("", "beta", "weight of log(red) (default 0.5065)", false, 0.5065, "b", cmd);
	TCLAP::ValueArg<std::string> wl(
		"", "wavelengths", "peak wavelengths blue,green,red in nm; sets alpha and beta = 1 - alpha",
		false, "", "l1,l2,l3", cmd);
	TCLAP::ValueArg<std::string> lin("", "linearise", "none|srgb|gamma (before the logs)", false, "none", "mode", cmd);
	TCLAP::ValueArg<double> gamma("", "gamma", "exponent for --linearise gamma", false, 2.2, "g", cmd);
	TCLAP::ValueArg<double> scale("", "scale", "grey levels per unit log response", false, 255.0, "s", cmd);
	cmd.parse(argc, argv);

	if (!std::filesystem::is_regular_file(in.getValue()))
		throw std::runtime_error("'" + in.getValue() + "': no such image file");
	const cv::Mat img = cv::imread(in.getValue(), cv::IMREAD_UNCHANGED);
	if (img.empty()) throw std::runtime_error("'" + in.getValue() + "': cannot read image");
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
		if (wl.isSet())
		{
			double l1, l2, l3;
			char c1, c2;
			std::istringstream s(wl.getValue());
			if (!(s >> l1 >> c1 >> l2 >> c2 >> l3))
				throw std::invalid_argument("--wavelengths: expected l1,l2,l3, got '" + wl.getValue() + "'");
			p = InvariantParams::FromWavelengths(l1, l2, l3);
		}
		else
			p = InvariantParams::FromAlphaBeta(alpha.getValue(), beta.getValue());
		p.linearisation = parseLinearisation(lin.getValue());
		p.gamma = gamma.getValue();
		p.scale = scale.getValue();
		std::cout << "invariant: " << p.asString() << "\n";
		InvariantTransform(p).apply(img, result);
	}
	shadyloc::io::writeAtomically(out.getValue(), [&](const std::string& tmp) {
		if (!cv::imwrite(tmp, result))
			throw std::runtime_error("'" + out.getValue() + "': cannot write image");
	});
	return 0;
}
shadyloc::apps::RegisterCommand reg("image", {"one image file -> mono or invariant image file", run});
}  // namespace
