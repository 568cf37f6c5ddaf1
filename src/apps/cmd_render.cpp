/* shadyloc render: top-down PNG of trajectories (TUM) and keyframe maps,
 * rendered offscreen through MRPT's 3D scene (no display needed). The one
 * render command; `render-traj` is its old name. */
#include "Command.h"
#include "CommandLine.h"
#include "LocalisedView.h"

#include <shadyloc/eval/Figures.h>
#include <shadyloc/eval/LocaliseOutputs.h>
#include <shadyloc/eval/TrajectoryError.h>
#include <shadyloc/io/FileHash.h>
#include <shadyloc/io/ImageFile.h>
#include <shadyloc/io/OutputTransaction.h>
#include <shadyloc/io/Tum.h>
#include <shadyloc/map/CKeyframeMap.h>
#include <shadyloc/render/TrajectorySnapshot.h>

#include <mrpt/3rdparty/tclap/CmdLine.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <sstream>

namespace cmd_render
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

// Colours of who held a frame (the same as docs/figures.md's figures).
using apps::kNoneColour;

/** The live trajectory of a `shadyloc localise` output folder, each segment
 * coloured by who held the frame it ends at (frames.csv's `used`). */
render::TrajectoryLayer localisedLayer(const std::string& dir, const std::string& name)
{
	namespace fs = std::filesystem;
	const std::string csvPath = (fs::path(dir) / "frames.csv").string(), tumPath = (fs::path(dir) / "trajectory.tum").string();
	if (!fs::is_directory(dir)) throw std::runtime_error("--localised '" + dir + "': not a directory (a shadyloc localise OUTDIR?)");
	const auto run = eval::readFramesCsv(csvPath);
	auto traj = io::readTum(tumPath);
	io::sortByTime(traj);
	render::TrajectoryLayer l;
	l.name = name;
	l.colour = kNoneColour;
	l.widthPx = 6.0;
	apps::HolderTally tally;
	size_t f = 0;  // frames and poses are both in time order
	for (const auto& p : traj)
	{
		while (f < run.frames.size() && run.frames[f].stamp < p.t - 1e-5) f++;
		if (f == run.frames.size() || std::fabs(run.frames[f].stamp - p.t) > 1e-5)
			throw std::runtime_error(
				"'" + tumPath + "': the pose at " + std::to_string(p.t) + " s has no frame in '" + csvPath +
				"' (not the same localise run?)");
		const auto& u = run.frames[f].used;
		tally.add(u);
		if (!l.points.empty()) l.segmentColours.push_back(apps::colourOfUsed(u));
		const auto x = p.T.translation();
		l.points.emplace_back(x.x(), x.y(), x.z());
	}
	if (l.points.size() < 2) throw std::runtime_error("'" + tumPath + "': fewer than two poses to draw");
	const size_t n = tally.total();
	for (const auto& row : tally.rows())
		l.legend.push_back(
			{name + ": " + row.what + ", " + std::to_string(row.frames) + " frames (" +
				 std::to_string(int(std::lround(100.0 * row.frames / n))) + " %)",
			 row.colour});
	return l;
}

/** --localised DIR must have been localised against the first -m map, and
 * --gt must be its live run's ground truth: drawn otherwise, the picture
 * shows a run against a map (or a truth) it never met, with nothing said. */
void checkLocalisedInputs(const std::string& dir, const std::string& mapFile, const std::string& gtFile)
{
	const std::string mapHash = eval::localiseProvenance(dir, "map_fnv1a64");
	if (!mapHash.empty() && mapHash != io::fnv1a64File(mapFile))
		throw std::invalid_argument(
			"--localised '" + dir + "' was localised against map '" + eval::localiseProvenance(dir, "map") +
			"' (its summary.json), not against -m '" + mapFile + "' (another file): give the run's own map first");
	if (gtFile.empty()) return;
	const std::string gtHash = eval::localiseProvenance(dir, "gt_fnv1a64");
	if (!gtHash.empty() && gtHash != io::fnv1a64File(gtFile))
		throw std::invalid_argument(
			"--gt '" + gtFile + "' is not the ground truth '" + eval::localiseProvenance(dir, "gt") + "' that --localised '" + dir +
			"' was localised with (its summary.json)");
	// Without a recorded truth, its times must at least meet the run's.
	auto gt = io::readTum(gtFile), live = io::readTum((std::filesystem::path(dir) / "trajectory.tum").string());
	io::sortByTime(gt);
	io::sortByTime(live);
	if (!gt.empty() && !live.empty() && (gt.back().t < live.front().t || gt.front().t > live.back().t))
		throw std::invalid_argument(
			"--gt '" + gtFile + "' (" + std::to_string(gt.front().t) + ".." + std::to_string(gt.back().t) +
			" s) shares no time with the run of --localised '" + dir + "' (" + std::to_string(live.front().t) + ".." +
			std::to_string(live.back().t) + " s): the ground truth of another run?");
}

mrpt::math::TPoint3D toPoint(const Eigen::Vector3d& x) { return mrpt::math::TPoint3D(x.x(), x.y(), x.z()); }

/** With --align, the pose that brings traj into the reference's frame
 * (identity without --align or for the first trajectory). */
Eigen::Isometry3d alignment(
	bool align, const io::Trajectory& reference, const io::Trajectory& traj, const std::string& file)
{
	if (!align || reference.empty()) return Eigen::Isometry3d::Identity();
	const auto err = eval::computeErrors(reference, traj);
	if (err.matched < 3)
		throw std::runtime_error(
			"'" + file + "': fewer than 3 poses share timestamps with the first trajectory: cannot --align");
	return err.T_gt_est;
}

/** The -t trajectories in a fixed palette; `reference` becomes the first. */
std::vector<render::TrajectoryLayer> trajectoryLayers(
	const std::vector<std::string>& specs, bool align, io::Trajectory& reference)
{
	static const mrpt::img::TColor palette[] = {
		{0, 0, 0}, {215, 40, 40}, {40, 160, 60}, {230, 140, 0}, {140, 60, 170}, {30, 90, 210}};
	std::vector<render::TrajectoryLayer> layers;
	for (const auto& spec : specs)
	{
		const auto [file, name] = fileAndName(spec);
		render::TrajectoryLayer l;
		l.name = name;
		l.colour = palette[layers.size() % std::size(palette)];
		l.widthPx = 3.0;
		auto traj = io::readTum(file);
		io::sortByTime(traj);
		const Eigen::Isometry3d T_ref_this = alignment(align, reference, traj, file);
		if (reference.empty()) reference = traj;
		for (const auto& p : traj) l.points.push_back(toPoint(T_ref_this * p.T.translation()));
		if (l.points.size() < 2) throw std::runtime_error("'" + file + "': fewer than two poses to draw");
		layers.push_back(l);
	}
	return layers;
}

/** --gt: the live run's ground truth in the map frame, through T_map_world
 * fitted to the keyframes' own poses and their ground truth. */
render::TrajectoryLayer liveTruthLayer(const CKeyframeMap& m, const std::string& file, const std::string& gtFile)
{
	io::Trajectory chain, truth;
	for (const auto& kf : m.keyframes())
		if (kf.T_gt_kf && !kf.predicted)
		{
			chain.push_back({kf.timestamp, kf.T_map_kf});
			truth.push_back({kf.timestamp, *kf.T_gt_kf});
		}
	if (chain.size() < 3)
		throw std::runtime_error(
			"--gt: keyframe map '" + file + "' has fewer than 3 keyframes with ground truth (survey it with --gt)");
	const Eigen::Isometry3d T_map_world = eval::computeErrors(chain, truth).T_gt_est;
	auto gt = io::readTum(gtFile);
	io::sortByTime(gt);
	render::TrajectoryLayer g;
	g.name = "ground truth of the live run";
	g.colour = {0, 0, 0};
	g.widthPx = 1.5;
	for (const auto& p : gt) g.points.push_back(toPoint(T_map_world * p.T.translation()));
	if (g.points.size() < 2) throw std::runtime_error("'" + gtFile + "': fewer than two poses to draw");
	return g;
}

/** A map as CKeyframeMap::getVisualizationInto draws it, brought into the
 * picture's frame by T_ref_map, with its legend (and its landmarks'). */
render::TObjectLayer mapLayer(
	const CKeyframeMap::Ptr& m, const std::string& name, const Eigen::Isometry3d& T_ref_map, bool landmarks)
{
	render::TObjectLayer l;
	std::ostringstream legend;
	legend << "map " << name << ": " << m->keyframeCount() << " keyframes, " << std::fixed << std::setprecision(0)
		   << m->pathLength() << " m";
	size_t predicted = 0;
	for (const auto& k : m->keyframes()) predicted += k.predicted;
	if (predicted) legend << " (orange: " << predicted << " after a VO break, predicted)";
	legend << "; chevrons every " << std::setprecision(0) << m->options.draw_frame_every_m << " m";
	// Experiences kept in frames of their own are not drawn (their poses are unrelated to the map frame).
	const auto drawn = [&m](const map::TMapKeyframe& k) { return m->frameOf(k.id) == 0; };
	const auto elsewhere = std::count_if(m->keyframes().begin(), m->keyframes().end(), [&](const auto& k) { return !drawn(k); });
	l.legend.push_back({legend.str(), CKeyframeMap::kDrawColourMeasured});
	if (elsewhere)
		l.legend.push_back(
			{"   not drawn: " + std::to_string(elsewhere) + " keyframes in frames of their own", CKeyframeMap::kDrawColourMeasured});
	for (const auto& k : m->keyframes())
		if (drawn(k)) l.extent.push_back(toPoint(T_ref_map * k.T_map_kf.translation()));
	if (landmarks)
		for (size_t c = 0; c < m->channels().size(); c++)
		{
			size_t n = 0;
			for (const auto& k : m->keyframes())
				for (const auto& s : k.channels[c])
					if (drawn(k) && s.P.z() <= m->options.draw_landmark_max_depth_m)
					{
						l.extent.push_back(toPoint(T_ref_map * (k.T_map_kf * s.P)));
						n++;
					}
			l.legend.push_back(
				{m->channels()[c].label + " landmarks (" + std::to_string(n) + ")", CKeyframeMap::drawColourOfChannel(c)});
		}
	l.make = [m, T_ref_map](double mPerPx) {
		CKeyframeMap::TDrawStyle style;
		style.path_width_m = 12 * mPerPx;  // a band under the 3 px trajectories
		style.marker_size_m = 18 * mPerPx;
		auto inMap = mrpt::opengl::CSetOfObjects::Create();
		m->getVisualizationInto(*inMap, style);
		inMap->setPose(mrpt::poses::CPose3D(mrpt::math::CMatrixDouble44(T_ref_map.matrix())));
		auto o = mrpt::opengl::CSetOfObjects::Create();
		o->insert(inMap);
		return o;
	};
	return l;
}

int run(int argc, char** argv)
{
	shadyloc::apps::CommandLine cli(
		"Renders trajectories (TUM) and keyframe maps (" + std::string(CKeyframeMap::kFileExtension) +
			") top-down into a PNG, offscreen (EGL). Each -t / -m is FILE or FILE:NAME; a map is drawn "
			"as CKeyframeMap::getVisualizationInto draws it (its path as a band, blue where measured and "
			"orange where predicted after a VO break, chevrons at keyframes), the trajectories over it in "
			"a fixed palette. With --localised OUTDIR (a `shadyloc localise` output folder) the live trajectory is "
			"drawn in the map frame, coloured by which localiser held each frame, over the keyframes of the "
			"first -m map (grey), with the live run's ground truth (--gt) brought into the map frame through "
			"the keyframes' ground truth.");
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
	TCLAP::ValueArg<std::string> localised(
		"", "localised",
		"a shadyloc localise output folder (DIR or DIR:NAME): its trajectory.tum coloured by frames.csv's `used`",
		false, "", "dir", cmd);
	TCLAP::ValueArg<std::string> liveGt(
		"", "gt", "with --localised: the live run's ground truth (TUM), drawn in the map frame of the first -m",
		false, "", "tum", cmd);
	TCLAP::SwitchArg landmarks("", "landmarks", "draw the maps' landmarks, coloured by channel", cmd);
	shadyloc::apps::NumberArg<unsigned> width(
		cli, "", "width", "image width [px]", 1000, "px", 16u, 16384u);
	shadyloc::apps::NumberArg<unsigned> height(
		cli, "", "height", "image height [px]", 800, "px", 16u, 16384u);
	cli.allowEmpty(title);
	if (const auto rc = cli.parse(argc, argv)) return *rc;
	if (trajs.getValue().empty() && maps.getValue().empty() && !localised.isSet())
		throw std::invalid_argument(
			"nothing to render: give trajectories (-t FILE[:NAME]), maps (-m FILE[:NAME]) and/or --localised DIR");
	if (localised.isSet() && align.getValue())
		throw std::invalid_argument("--localised draws in the map frame: --align (to the first -t) does not apply");
	if (liveGt.isSet() && (!localised.isSet() || maps.getValue().empty()))
		throw std::invalid_argument("--gt needs --localised and a map (-m) whose keyframes carry ground truth");
	// The picture is the one output; no input may be overwritten by it.
	io::OutputTransaction outputs;
	for (const auto& spec : trajs.getValue()) outputs.addInput(fileAndName(spec).first, "trajectory");
	for (const auto& spec : maps.getValue()) outputs.addInput(fileAndName(spec).first, "map");
	if (localised.isSet()) outputs.addInput(fileAndName(localised.getValue()).first, "localise output");
	if (liveGt.isSet()) outputs.addInput(liveGt.getValue(), "ground truth");
	const std::string outTmp = outputs.addFile(out.getValue(), "output image");
	io::checkImageWritable(out.getValue());
	if (localised.isSet() && !maps.getValue().empty())
		checkLocalisedInputs(
			fileAndName(localised.getValue()).first, fileAndName(maps.getValue().front()).first,
			liveGt.isSet() ? liveGt.getValue() : "");

	// The first trajectory's frame is the picture's, for --align.
	io::Trajectory reference;
	std::vector<render::TrajectoryLayer> layers = trajectoryLayers(trajs.getValue(), align.getValue(), reference);
	std::vector<render::TObjectLayer> objects;
	std::string singleKeyframe;	// maps of one keyframe: a single point
	std::vector<render::TrajectoryLayer> underneath;  // --localised: the maps' keyframes, under every path
	for (const auto& spec : maps.getValue())
	{
		const auto [file, name] = fileAndName(spec);
		const CKeyframeMap::Ptr m = CKeyframeMap::LoadFromFile(file);
		if (m->isEmpty()) throw std::runtime_error("keyframe map '" + file + "': no keyframes to draw");
		if (m->keyframeCount() == 1) singleKeyframe += (singleKeyframe.empty() ? "" : ", ") + ("'" + file + "'");
		if (localised.isSet())
		{
			if (liveGt.isSet() && underneath.empty()) layers.push_back(liveTruthLayer(*m, file, liveGt.getValue()));
			underneath.push_back(apps::keyframesLayer(*m, name));
			continue;
		}
		m->options.draw_landmarks = landmarks.getValue();
		// --align fits the measured keyframes of the map's first segment.
		io::Trajectory chain;
		for (const auto& k : m->keyframes())
			if (!k.predicted) chain.push_back({k.timestamp, k.T_map_kf});
		objects.push_back(mapLayer(m, name, alignment(align.getValue(), reference, chain, file), landmarks.getValue()));
	}
	if (localised.isSet())
	{
		const auto [dir, name] = fileAndName(localised.getValue());
		const auto live = localisedLayer(dir, name == std::filesystem::path(dir).stem().string() ? "live" : name);
		layers.insert(layers.begin(), live);
	}
	layers.insert(layers.begin(), underneath.begin(), underneath.end());
	if (layers.empty() && align.getValue())
		throw std::invalid_argument("--align aligns to the first trajectory: give one with -t");

	render::SnapshotOptions o;
	o.title = title.getValue();
	o.width = width.getValue();
	o.height = height.getValue();
	o.upAxis = up.getValue()[0];
	// The renderer knows only its temporary output: name the inputs here.
	size_t points = 0;
	for (const auto& l : layers) points += l.points.size();
	for (const auto& l : objects) points += l.extent.size();
	if (points < 2)
		throw std::runtime_error(
			"nothing to draw: fewer than two points" +
			(singleKeyframe.empty() ? std::string() : " (keyframe map " + singleKeyframe + ": a single keyframe)"));
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
}  // namespace cmd_render
