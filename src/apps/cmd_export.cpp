/* shadyloc export kitti: stereo rawlog -> KITTI odometry layout. */
#include "Command.h"
#include "CommandLine.h"

#include <shadyloc/datasets/Kitti.h>


#include <cstring>
#include <iostream>

namespace cmd_export
{
using namespace shadyloc::datasets;

int runKitti(int argc, char** argv)
{
	shadyloc::apps::CommandLine cli(
		"Writes the stereo observations of one sensor as a KITTI odometry sequence: "
		"ROOT/sequences/NN/{image_2,image_3,calib.txt,times.txt}, and ROOT/poses/NN.txt from a "
		"TUM ground truth when given.");
	auto& cmd = cli.cmd();
	TCLAP::ValueArg<std::string> in("i", "input", "input rawlog", true, "", "in.rawlog", cmd);
	TCLAP::ValueArg<std::string> out("o", "output", "KITTI root directory", true, "", "ROOT", cmd);
	TCLAP::ValueArg<std::string> seq("s", "sequence", "sequence number", false, "00", "NN", cmd);
	TCLAP::ValueArg<std::string> label(
		"", "sensor-label", "stereo observations to export", false, "CAMERA", "label", cmd);
	TCLAP::ValueArg<std::string> gt("", "gt", "TUM ground truth -> poses/NN.txt", false, "", "gt.tum", cmd);
	shadyloc::apps::NumberArg<double> tol(
		cli, "", "gt-tolerance", "max time difference frame / ground-truth pose [s] (>= 0)", 1e-3, "s", 0.0);
	TCLAP::SwitchArg abs("", "absolute-times", "times.txt in absolute seconds (default: since frame 0)", cmd);
	TCLAP::SwitchArg quiet("q", "quiet", "no progress output", cmd);
	if (const auto rc = cli.parse(argc, argv)) return *rc;

	KittiExporter exp;
	exp.options.sequence = seq.getValue();
	exp.options.sensorLabel = label.getValue();
	exp.options.groundTruthTum = gt.getValue();
	exp.options.gtTimeTolerance = tol.getValue();
	exp.options.absoluteTimes = abs.getValue();
	exp.setMinLoggingLevel(quiet.getValue() ? mrpt::system::LVL_WARN : mrpt::system::LVL_INFO);
	const auto r = exp.run(in.getValue(), out.getValue());
	std::cout << "Exported " << r.frames << " stereo frame(s) to '"
			  << kittiSequenceDir(out.getValue(), seq.getValue()) << "'"
			  << (r.poses ? " with poses" : "") << "\n";
	return 0;
}

int run(int argc, char** argv)
{
	if (argc >= 2 && !std::strcmp(argv[1], "--version"))
	{
		std::cout << argv[0] << " " << shadyloc::apps::version() << "\n";
		return 0;
	}
	if (argc < 2 || !std::strcmp(argv[1], "--help") || !std::strcmp(argv[1], "-h"))
	{
		(argc < 2 ? std::cerr : std::cout)
			<< "usage: shadyloc export kitti -i in.rawlog -o ROOT [--sequence NN] "
			   "[--sensor-label CAMERA] [--gt gt.tum]   (shadyloc export kitti --help)\n";
		return argc < 2 ? 2 : 0;
	}
	if (std::strcmp(argv[1], "kitti") != 0)
	{
		std::cerr << "shadyloc export: unknown format '" << argv[1] << "' (known: kitti)\n";
		return 2;
	}
	std::string argv0 = std::string(argv[0]) + " kitti";
	argv[1] = argv0.data();
	return runKitti(argc - 1, argv + 1);
}

shadyloc::apps::RegisterCommand reg(
	"export", {"stereo rawlog -> KITTI odometry layout (export kitti --help)", run});
}  // namespace cmd_export
