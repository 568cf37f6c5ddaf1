/* shadyloc render: top-down PNG of trajectories (TUM) and keyframe maps,
 * rendered offscreen through MRPT's 3D scene (no display needed). The one
 * render command; `render-traj` is its old name. */
#include "Command.h"
#include "CommandLine.h"

#include <shadyloc/eval/TrajectoryError.h>
#include <shadyloc/io/ImageFile.h>
#include <shadyloc/io/OutputTransaction.h>
#include <shadyloc/io/Tum.h>
#include <shadyloc/map/CKeyframeMap.h>
#include <shadyloc/render/TrajectorySnapshot.h>

#include <mrpt/3rdparty/tclap/CmdLine.h>

#include <filesystem>
#include <iomanip>
#include <iostream>
#include <sstream>

namespace
{
using namespace shadyloc;

/** "FILE" or "FILE:NAME" (a path that exists with its colon is a file). */
std::pair<std::string, std::string> fileAndName(const std::string& spec)
{
	const auto colon = spec.rfind(':');
	if (colon != std::string::npos && !std::filesystem::exists(spec))
		return {spec.substr(0, colon), spec.substr(colon + 1)};
	return {spec, std::filesystem::path(spec).stem().string()};
}

int run(int argc, char** argv)
{
	shadyloc::apps::CommandLine cli(
		"Renders trajectories (TUM) and keyframe maps (" + std::string(CKeyframeMap::kFileExtension) +
			") top-down into a PNG, offscreen (EGL). Each -t / -m is FILE or FILE:NAME; a map is drawn "
			"as CKeyframeMap::getVisualizationInto draws it (its path as a band, blue where measured and "
			"orange where predicted after a VO break, chevrons at keyframes), the trajectories over it in "
			"a fixed palette.");
	auto& cmd = cli.cmd();
	TCLAP::MultiArg<std::string> trajs("t", "traj", "TUM trajectory (FILE or FILE:NAME)", false, "tum", cmd);
	TCLAP::MultiArg<std::string> maps(
		"m", "map", "keyframe map (FILE or FILE:NAME)", false, std::string("map") + CKeyframeMap::kFileExtension, cmd);
	TCLAP::ValueArg<std::string> out("o", "output", "output PNG", true, "", "out.png", cmd);
	TCLAP::ValueArg<std::string> title("", "title", "title text", false, "", "text", cmd);
	std::vector<std::string> upAxisNames{"x", "y", "z", "a"};
	TCLAP::ValuesConstraint<std::string> upAxes(upAxisNames);
	TCLAP::ValueArg<std::string> up(
		"", "up", "axis out of the picture: x, y (camera frames), z, or a (auto)", false, "a", &upAxes, cmd);
	TCLAP::SwitchArg align(
		"", "align",
		"align every other trajectory and every map (by its keyframes' timestamps) to the first trajectory "
		"(SE(3), no scale), e.g. a VO estimate or a map to its ground truth",
		cmd);
	TCLAP::SwitchArg landmarks("", "landmarks", "draw the maps' landmarks, coloured by channel", cmd);
	shadyloc::apps::NumberArg<unsigned> width(
		cli, "", "width", "image width [px]", 1000, "px", 16u, 16384u);
	shadyloc::apps::NumberArg<unsigned> height(
		cli, "", "height", "image height [px]", 800, "px", 16u, 16384u);
	cli.allowEmpty(title);
	if (const auto rc = cli.parse(argc, argv)) return *rc;
	if (trajs.getValue().empty() && maps.getValue().empty())
		throw std::invalid_argument("nothing to render: give trajectories (-t FILE[:NAME]) and/or maps (-m FILE[:NAME])");
	// The picture is the one output; no input may be overwritten by it.
	io::OutputTransaction outputs;
	for (const auto& spec : trajs.getValue()) outputs.addInput(fileAndName(spec).first, "trajectory");
	for (const auto& spec : maps.getValue()) outputs.addInput(fileAndName(spec).first, "map");
	const std::string outTmp = outputs.addFile(out.getValue(), "output image");
	io::checkImageWritable(out.getValue());

	// The first trajectory's frame is the picture's, for --align.
	io::Trajectory reference;
	auto alignment = [&](const io::Trajectory& traj, const std::string& file) {
		if (!align.getValue() || reference.empty()) return Eigen::Isometry3d::Identity();
		const auto err = eval::computeErrors(reference, traj);
		if (err.matched < 3)
			throw std::runtime_error(
				"'" + file + "': fewer than 3 poses share timestamps with the first trajectory: cannot --align");
		return err.T_gt_est;
	};
	auto toPoint = [](const Eigen::Vector3d& x) { return mrpt::math::TPoint3D(x.x(), x.y(), x.z()); };

	static const mrpt::img::TColor palette[] = {
		{0, 0, 0}, {215, 40, 40}, {40, 160, 60}, {230, 140, 0}, {140, 60, 170}, {30, 90, 210}};
	std::vector<render::TrajectoryLayer> layers;
	for (const auto& spec : trajs.getValue())
	{
		const auto [file, name] = fileAndName(spec);
		render::TrajectoryLayer l;
		l.name = name;
		l.colour = palette[layers.size() % std::size(palette)];
		l.widthPx = 3.0;
		auto traj = io::readTum(file);
		io::sortByTime(traj);
		const Eigen::Isometry3d T_ref_this = alignment(traj, file);
		if (reference.empty()) reference = traj;
		for (const auto& p : traj) l.points.push_back(toPoint(T_ref_this * p.T.translation()));
		if (l.points.size() < 2) throw std::runtime_error("'" + file + "': fewer than two poses to draw");
		layers.push_back(l);
	}

	std::vector<render::TObjectLayer> objects;
	for (const auto& spec : maps.getValue())
	{
		const auto [file, name] = fileAndName(spec);
		const CKeyframeMap::Ptr m = CKeyframeMap::LoadFromFile(file);
		if (m->isEmpty()) throw std::runtime_error("keyframe map '" + file + "': no keyframes to draw");
		m->options.draw_landmarks = landmarks.getValue();
		// --align fits the measured keyframes of the map's first segment.
		io::Trajectory chain;
		for (const auto& k : m->keyframes())
			if (!k.predicted) chain.push_back({k.timestamp, k.T_map_kf});
		const Eigen::Isometry3d T_ref_map = alignment(chain, file);
		render::TObjectLayer l;
		std::ostringstream legend;
		legend << "map " << name << ": " << m->keyframeCount() << " keyframes, " << std::fixed
			   << std::setprecision(0) << m->pathLength() << " m";
		size_t predicted = 0;
		for (const auto& k : m->keyframes()) predicted += k.predicted;
		if (predicted) legend << " (orange: " << predicted << " after a VO break, predicted)";
		legend << "; chevrons every " << std::setprecision(0) << m->options.draw_frame_every_m << " m";
		l.legend.push_back({legend.str(), CKeyframeMap::kDrawColourMeasured});
		for (const auto& k : m->keyframes()) l.extent.push_back(toPoint(T_ref_map * k.T_map_kf.translation()));
		if (landmarks.getValue())
			for (size_t c = 0; c < m->channels().size(); c++)
			{
				size_t n = 0;
				for (const auto& k : m->keyframes())
					for (const auto& s : k.channels[c])
						if (s.P.z() <= m->options.draw_landmark_max_depth_m)
						{
							l.extent.push_back(toPoint(T_ref_map * (k.T_map_kf * s.P)));
							n++;
						}
				l.legend.push_back(
					{m->channels()[c].label + " landmarks (" + std::to_string(n) + ")", CKeyframeMap::drawColourOfChannel(c)});
			}
		l.make = [m, T_ref_map](double mPerPx) {
			CKeyframeMap::TDrawStyle style;
			style.path_width_m = 12 * mPerPx;	 // a band under the 3 px trajectories
			style.marker_size_m = 18 * mPerPx;
			auto inMap = mrpt::opengl::CSetOfObjects::Create();
			m->getVisualizationInto(*inMap, style);
			inMap->setPose(mrpt::poses::CPose3D(mrpt::math::CMatrixDouble44(T_ref_map.matrix())));
			auto o = mrpt::opengl::CSetOfObjects::Create();
			o->insert(inMap);
			return o;
		};
		objects.push_back(l);
	}
	if (layers.empty() && align.getValue())
		throw std::invalid_argument("--align aligns to the first trajectory: give one with -t");

	render::SnapshotOptions o;
	o.title = title.getValue();
	o.width = width.getValue();
	o.height = height.getValue();
	o.upAxis = up.getValue()[0];
	render::renderTrajectories(layers, o, outTmp, objects);
	outputs.commit();
	std::cout << "wrote " << out.getValue() << "\n";
	return 0;
}

int runOldName(int argc, char** argv)
{
	std::cerr << "shadyloc render-traj: renamed to `shadyloc render` (same options, plus -m for maps); "
				 "the old name will go\n";
	return run(argc, argv);
}

shadyloc::apps::RegisterCommand reg(
	"render", {"top-down PNG of trajectories and keyframe maps, offscreen (-t traj.tum -m map.kfmap -o out.png)", run});
shadyloc::apps::RegisterCommand regOld("render-traj", {"old name of `render` (deprecated)", runOldName});
}  // namespace
