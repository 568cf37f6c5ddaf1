/* ShadyLoc — a localisation run over its map, offscreen (LocalisedView.h). */
#include "LocalisedView.h"

#include <cstdio>
#include <iomanip>
#include <sstream>

namespace shadyloc::apps
{
using render::renderTrajectories;
using render::SnapshotOptions;
using render::TrajectoryLayer;

namespace
{
mrpt::math::TPoint3D toPoint(const Eigen::Vector3d& p) { return {p.x(), p.y(), p.z()}; }
}  // namespace

mrpt::img::TColor colourOfUsed(const std::string& used)
{
	if (used == "mono") return kMonoColour;
	if (used == "invariant") return kInvariantColour;
	return used == "joint" ? kJointColour : kNoneColour;
}

void HolderTally::add(const std::string& used)
{
	size_t& n = used == "mono" ? m_mono : used == "invariant" ? m_invariant : used == "joint" ? m_joint : m_none;
	n++;
}

std::vector<HolderTally::TRow> HolderTally::rows() const
{
	std::vector<TRow> r{{"mono fix", m_mono, kMonoColour}, {"invariant fix", m_invariant, kInvariantColour}};
	if (m_joint > 0) r.push_back({"joint fix", m_joint, kJointColour});
	r.push_back({"no fix (VO)", m_none, kNoneColour});
	return r;
}

std::string viewFileName(size_t frame)
{
	char name[32];
	std::snprintf(name, sizeof(name), "frame_%06zu.png", frame);
	return name;
}

TrajectoryLayer keyframesLayer(const CKeyframeMap& map, const std::string& name)
{
	TrajectoryLayer k;
	k.colour = {150, 150, 150};
	k.widthPx = 16;
	k.markerPx = 6;
	k.markerColour = {90, 90, 90};
	for (const auto& kf : map.keyframes()) k.points.push_back(toPoint(kf.T_map_kf.translation()));
	std::ostringstream legend;
	legend << "map " << name << ": " << map.keyframeCount() << " keyframes (squares), " << std::fixed
		   << std::setprecision(0) << map.pathLength() << " m";
	k.name = legend.str();
	if (k.points.size() == 1) k.points.push_back(k.points.front());
	return k;
}

std::vector<TrajectoryLayer> localisedViewLayers(
	const CKeyframeMap& map, const std::vector<localisation::TLocalisationUpdate>& ups)
{
	TrajectoryLayer live;
	live.name = "live";
	live.widthPx = 6.0;
	HolderTally tally;
	for (const auto& u : ups)
	{
		if (!u.placeKnown) continue;
		tally.add(u.used);
		if (!live.points.empty()) live.segmentColours.push_back(colourOfUsed(u.used));
		live.points.push_back(toPoint(u.T_map_live.translation()));
	}
	for (const auto& row : tally.rows())
		live.legend.push_back({row.what + ": " + std::to_string(row.frames) + (live.legend.empty() ? " frames" : ""), row.colour});
	std::vector<TrajectoryLayer> layers{keyframesLayer(map, map.runs().empty() ? "" : map.runs().front())};
	if (live.points.size() >= 2) layers.push_back(live);
	// The latest pose: 1.5 m along its optical axis (z of the camera).
	for (auto it = ups.rbegin(); it != ups.rend(); ++it)
		if (it->placeKnown)
		{
			TrajectoryLayer now;
			now.name = "now (frame " + std::to_string(it->frame) + ")";
			now.colour = {0, 0, 0};
			now.widthPx = 9.0;
			now.points = {toPoint(it->T_map_live.translation()), toPoint(it->T_map_live * Eigen::Vector3d(0, 0, 1.5))};
			layers.push_back(now);
			break;
		}
	return layers;
}

void renderLocalisedView(
	const CKeyframeMap& map, const std::vector<localisation::TLocalisationUpdate>& ups, const SnapshotOptions& opts,
	const std::string& pngPath)
{
	renderTrajectories(localisedViewLayers(map, ups), opts, pngPath);
}

}  // namespace shadyloc::apps
