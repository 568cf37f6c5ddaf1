/* shadyloc render-traj: top-down PNG of one or more TUM trajectories, rendered
 * offscreen through MRPT's 3D scene (no display needed). */
#include "Command.h"
#include "CommandLine.h"

#include <shadyloc/eval/TrajectoryError.h>
#include <shadyloc/io/ImageFile.h>
#include <shadyloc/io/OutputTransaction.h>
#include <shadyloc/render/TrajectorySnapshot.h>


#include <filesystem>
#include <iostream>

namespace
{
int run(int argc, char** argv)
{
	shadyloc::apps::CommandLine cli(
		"Renders TUM trajectories top-down into a PNG, offscreen (EGL). Each -t is "
		"FILE or FILE:NAME; colours follow a fixed palette.");
	auto& cmd = cli.cmd();
	TCLAP::MultiArg<std::string> trajs("t", "traj", "TUM trajectory (FILE or FILE:NAME)", true, "tum", cmd);
	TCLAP::ValueArg<std::string> out("o", "output", "output PNG", true, "", "out.png", cmd);
	TCLAP::ValueArg<std::string> title("", "title", "title text", false, "", "text", cmd);
	std::vector<std::string> axes{"x", "y", "z", "a"};
	TCLAP::ValuesConstraint<std::string> axesC(axes);
	TCLAP::ValueArg<std::string> up(
		"", "up", "axis out of the picture: x, y (camera frames), z, or a (auto)", false, "a", &axesC, cmd);
	TCLAP::SwitchArg align(
		"", "align", "align every trajectory to the first (SE(3), no scale, by timestamps), "
		"e.g. a VO estimate to its ground truth", cmd);
	// Offscreen framebuffers of Mesa's software renderer stop at 16384 px.
	shadyloc::apps::NumberArg<unsigned> width(cli, "", "width", "image width [px], 16..16384", 1000, "px", 16, 16384);
	shadyloc::apps::NumberArg<unsigned> height(cli, "", "height", "image height [px], 16..16384", 800, "px", 16, 16384);
	cli.allowEmpty(title);
	if (const auto rc = cli.parse(argc, argv)) return *rc;

	shadyloc::io::OutputTransaction outputs;
	std::vector<std::pair<std::string, std::string>> files;	 // file, name
	for (const auto& spec : trajs.getValue())
	{
		auto colon = spec.rfind(':');
		std::string file = spec, name = std::filesystem::path(spec).stem().string();
		if (colon != std::string::npos && !std::filesystem::exists(spec))
			file = spec.substr(0, colon), name = spec.substr(colon + 1);
		outputs.addInput(file, "trajectory");
		files.emplace_back(file, name);
	}
	const std::string outTmp = outputs.addFile(out.getValue(), "output image");
	shadyloc::io::checkImageWritable(out.getValue());

	static const mrpt::img::TColor palette[] = {
		{0, 0, 0}, {215, 40, 40}, {30, 90, 210}, {40, 160, 60}, {230, 140, 0}, {140, 60, 170}};
	std::vector<shadyloc::render::TrajectoryLayer> layers;
	shadyloc::eval::Trajectory reference;  // the first trajectory, for --align
	for (const auto& [file, name] : files)
	{
		shadyloc::render::TrajectoryLayer l;
		l.name = name;
		l.colour = palette[layers.size() % std::size(palette)];
		const auto traj = shadyloc::eval::readTum(file);
		Eigen::Isometry3d T_ref_this = Eigen::Isometry3d::Identity();
		if (align.getValue() && !reference.empty())
		{
			const auto err = shadyloc::eval::computeErrors(reference, traj);
			if (err.matched < 3)
				throw std::runtime_error("'" + file + "': fewer than 3 poses share timestamps with the first trajectory: cannot --align");
			T_ref_this = err.T_gt_est;
		}
		if (reference.empty()) reference = traj;
		for (const auto& p : traj)
		{
			const Eigen::Vector3d x = T_ref_this * p.T.translation();
			l.points.push_back({x.x(), x.y(), x.z()});
		}
		if (l.points.size() < 2)
			throw std::runtime_error("'" + file + "': fewer than two poses to draw");
		layers.push_back(l);
	}
	shadyloc::render::SnapshotOptions o;
	o.title = title.getValue();
	o.width = width.getValue();
	o.height = height.getValue();
	o.upAxis = up.getValue()[0];
	shadyloc::render::renderTrajectories(layers, o, outTmp);
	outputs.commit();
	std::cout << "wrote " << out.getValue() << "\n";
	return 0;
}
shadyloc::apps::RegisterCommand reg("render-traj", {"top-down PNG of TUM trajectories (offscreen)", run});
}  // namespace
