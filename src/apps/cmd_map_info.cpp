/* shadyloc map-info: the summary of a keyframe map. */
#include "Command.h"
#include "CommandLine.h"

#include <shadyloc/eval/TrajectoryError.h>
#include <shadyloc/io/OutputTransaction.h>
#include <shadyloc/map/CKeyframeMap.h>

#include <mrpt/3rdparty/tclap/CmdLine.h>

#include <iomanip>
#include <iostream>

namespace cmd_map_info
{
using namespace shadyloc;

int run(int argc, char** argv)
{
	shadyloc::apps::CommandLine cli(
		"Prints a keyframe map's summary: keyframes, path length, runs, segments, channels and their "
		"descriptor parameters, stored bytes per channel, options; with ground truth stored beside the "
		"keyframes, the chain's error against it (ATE after SE(3) alignment, drift).");
	auto& cmd = cli.cmd();
	TCLAP::UnlabeledValueArg<std::string> in("map", "map file", true, "", "map.kfmap", cmd);
	TCLAP::SwitchArg perKf("k", "keyframes", "one line per keyframe", cmd);
	TCLAP::ValueArg<std::string> stripGt(
		"", "strip-gt",
		"write a copy of the map without its ground truth to OUT (written whole or not at all) and exit", false, "",
		"OUT.kfmap", cmd);
	if (const auto rc = cli.parse(argc, argv)) return *rc;

	const auto m = CKeyframeMap::LoadFromFile(in.getValue());
	m->reportLoadProblems(std::cerr, in.getValue());
	if (stripGt.isSet())
	{
		// The copy differs from the map in the ground truth alone: localising
		// against either gives byte-identical outputs (docs/localisation.md).
		io::OutputTransaction tx;
		tx.addInput(in.getValue(), "map");
		const std::string tmp = tx.addFile(stripGt.getValue(), "--strip-gt");
		const size_t n = m->stripGroundTruth();
		m->saveToFile(tmp);
		tx.commit();
		std::cout << in.getValue() << ": ground truth removed from " << n << " of " << m->keyframeCount()
				  << " keyframes -> " << stripGt.getValue() << "\n";
		return 0;
	}
	std::cout << in.getValue() << ": " << m->asString() << "\n";
	eval::Trajectory est, gt;
	for (const auto& k : m->keyframes())
		if (k.T_gt_kf && !k.predicted)
		{
			est.push_back({k.timestamp, k.T_map_kf});
			gt.push_back({k.timestamp, *k.T_gt_kf});
		}
	if (est.size() >= 3)
	{
		const auto e = eval::computeErrors(gt, est, 1e-6);
		std::cout << std::fixed << std::setprecision(3) << "  chain vs ground truth (" << e.matched
				  << " keyframes of the first segment, " << std::setprecision(1) << e.path_length
				  << " m): ATE RMSE " << std::setprecision(3) << e.ate_rmse << " m, max " << e.ate_max
				  << " m; drift " << std::setprecision(2) << e.kitti_trans_pct << " %, " << std::setprecision(4)
				  << e.kitti_rot_deg_per_m << " deg/m\n";
	}
	if (perKf.getValue())
	{
		std::cout << "id run segment frame timestamp predicted x y z chain_m";
		for (const auto& c : m->channels()) std::cout << " n_" << c.label;
		std::cout << "\n" << std::setprecision(3);
		for (const auto& k : m->keyframes())
		{
			const auto& t = k.T_map_kf.translation();
			std::cout << k.id << ' ' << k.run << ' ' << k.segment << ' ' << k.frame << ' ' << k.timestamp << ' '
					  << k.predicted << ' ' << t.x() << ' ' << t.y() << ' ' << t.z() << ' ' << m->chainDistance(k.id);
			for (const auto& c : k.channels) std::cout << ' ' << c.size();
			std::cout << "\n";
		}
	}
	return 0;
}
shadyloc::apps::RegisterCommand reg("map-info", {"summary of a keyframe map (map-info map.kfmap [-k] [--strip-gt OUT.kfmap])", run});
}  // namespace cmd_map_info
