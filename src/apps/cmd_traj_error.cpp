/* shadyloc traj-error: ATE, RPE and KITTI-style drift of a trajectory. */
#include "Command.h"
#include "CommandLine.h"

#include <shadyloc/eval/TrajectoryError.h>
#include <shadyloc/io/Tum.h>


#include <iostream>

namespace cmd_traj_error
{
int run(int argc, char** argv)
{
	shadyloc::apps::CommandLine cli(
		"Trajectory error of an estimate against ground truth (both TUM): poses associated by "
		"timestamp, SE(3) alignment without scale (Horn/Umeyama), ATE RMSE, per-step RPE, and "
		"KITTI-style translational [%] / rotational [deg/m] error over sub-sequences of 100..800 m "
		"(scaled down for runs shorter than 1 km; the lengths used are printed).");
	auto& cmd = cli.cmd();
	TCLAP::ValueArg<std::string> gt("", "gt", "ground truth (TUM)", true, "", "gt.tum", cmd);
	TCLAP::ValueArg<std::string> est("", "est", "estimate (TUM)", true, "", "traj.tum", cmd);
	shadyloc::apps::NumberArg<double> maxDt(
		cli, "", "max-dt", "largest timestamp difference of an associated pair [s] (>= 0)", 0.02, "s", 0.0);
	if (const auto rc = cli.parse(argc, argv)) return *rc;
	auto g = shadyloc::io::readTum(gt.getValue());
	auto e = shadyloc::io::readTum(est.getValue());
	shadyloc::io::sortByTime(g);
	shadyloc::io::sortByTime(e);
	const auto r = shadyloc::eval::computeErrors(g, e, maxDt.getValue());
	std::cout << "ground truth: " << gt.getValue() << " (" << g.size() << " poses)\n"
			  << "estimate:     " << est.getValue() << " (" << e.size() << " poses)\n"
			  << r.asText();
	return 0;
}
shadyloc::apps::RegisterCommand reg(
	"traj-error", {"ATE/RPE/KITTI-style drift of a TUM trajectory (--gt gt.tum --est traj.tum)", run});
}  // namespace cmd_traj_error
