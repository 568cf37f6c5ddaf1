/* ShadyLoc — a localisation run's output files (LocaliseOutputs.h, docs/localisation.md). */
#include <shadyloc/eval/LocaliseOutputs.h>
#include <shadyloc/io/AtomicFile.h>
#include <shadyloc/io/Csv.h>
#include <shadyloc/io/FileHash.h>
#include <shadyloc/io/Tum.h>

#include "Json.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <sstream>
#include <vector>

namespace shadyloc::eval
{
using localisation::toString;

namespace
{
double percentile(std::vector<double> v, double p)
{
	if (v.empty()) return 0;
	std::sort(v.begin(), v.end());
	return v[static_cast<size_t>(std::round(p * (v.size() - 1)))];
}

void poseFields(std::ostream& o, const Eigen::Isometry3d& T)
{
	const Eigen::Quaterniond q(T.linear());
	const auto& t = T.translation();
	o << std::setprecision(6) << t.x() << ',' << t.y() << ',' << t.z() << ',' << std::setprecision(9) << q.x() << ','
	  << q.y() << ',' << q.z() << ',' << q.w();
}
}  // namespace

namespace
{
/** frames.csv's columns: the mono and invariant localisers by name, any
 * other after them; ground-truth and oracle columns when there are such. */
struct TFramesColumns
{
	std::vector<std::string> extra;	 //!< localisers with other names
	std::vector<std::string> perChannel;  //!< mono, invariant, then the extra ones
	std::vector<std::string> localisers;  //!< policy order
	bool gt = false, oracle = false;

	TFramesColumns(const Updates& ups, const TEvaluation& ev) : gt(ev.ground_truth)
	{
		perChannel = {"mono", "invariant"};
		for (const auto& r : ups.front().localisers)
		{
			localisers.push_back(r.channel);
			if (std::find(perChannel.begin(), perChannel.begin() + 2, r.channel) == perChannel.begin() + 2)
				extra.push_back(r.channel);
		}
		perChannel.insert(perChannel.end(), extra.begin(), extra.end());
		oracle = !ups.front().oracle.empty();
	}

	std::string header() const
	{
		std::string h =
			"frame,stamp,distance_m,in_map,mono_ok,invariant_ok,used,kf_run,kf_frame,kf_id,kf_stamp,mono_inliers,"
			"invariant_inliers,rel_x,rel_y,rel_z,rel_qx,rel_qy,rel_qz,rel_qw";
		for (const auto& e : extra) h += "," + e + "_ok," + e + "_inliers";
		for (const auto& c : perChannel)
			for (const char* f : {"status", "matches", "gate_px", "sigma_m", "kf_id", "rel_x", "rel_y", "rel_z", "rel_qx", "rel_qy", "rel_qz", "rel_qw"})
				h += "," + c + "_" + f;
		h += ",global_search,global_inliers,global_runner_up,frames_since_fix,vo_from";
		if (gt) h += ",gt_distance_m,used_true,used_err_m,used_err_deg";
		if (oracle)
			for (const auto& l : localisers) h += "," + l + "_oracle";
		return h;
	}
};

/** The fix used (keyframe, pose in it) and each named localiser's verdict and inliers. */
void fixColumns(std::ostream& o, const localisation::TLocalisationUpdate& u, const CKeyframeMap& map, const TFramesColumns& cols)
{
	const auto okOf = [&](const std::string& c) {
		const auto* r = u.result(c);
		return r ? std::to_string(int(r->accepted())) : std::string();
	};
	const auto inlOf = [&](const std::string& c) {
		const auto* r = u.result(c);
		return r ? std::to_string(r->inliers) : std::string();
	};
	o << ',' << okOf("mono") << ',' << okOf("invariant") << ',' << (u.localised() ? u.used : "none");
	if (u.localised())
		o << ',' << map.runs().at(u.kf_run) << ',' << u.kf_frame << ',' << u.kf_id << ',' << std::setprecision(6) << u.kf_stamp;
	else
		o << ",,,,";
	o << ',' << inlOf("mono") << ',' << inlOf("invariant") << ',';
	if (u.localised())
		poseFields(o, u.T_kf_live);
	else
		o << ",,,,,,";
	for (const auto& e : cols.extra) o << ',' << okOf(e) << ',' << inlOf(e);
}

/** Each localiser's status, matches, gate, sigma and accepted pose. */
void channelColumns(std::ostream& o, const localisation::TLocalisationUpdate& u, const TFramesColumns& cols)
{
	for (const auto& c : cols.perChannel)
	{
		const auto* r = u.result(c);
		o << ',' << (r ? toString(r->status) : std::string()) << ',' << (r ? std::to_string(r->matches) : std::string())
		  << ',';
		if (r) o << std::setprecision(1) << r->gate.median_axis_px;
		o << ',';
		if (r && r->solved) o << std::setprecision(4) << r->sigma_m;
		if (r && r->accepted())
		{
			o << ',' << r->kf_id << ',';
			poseFields(o, r->T_kf_live);
		}
		else
			o << ",,,,,,,,";
	}
}

/** Ground truth's distance and the used fix's truth and error. */
void truthColumns(std::ostream& o, const TFrameEval& f)
{
	o << ',' << std::setprecision(3) << f.distance_m << ','
	  << (f.used == FixTruth::None ? std::string() : std::to_string(int(f.used))) << ',';
	if (f.used_err_m >= 0)
		o << std::setprecision(4) << f.used_err_m << ',' << f.used_err_deg;
	else
		o << ',';
}

void frameRow(
	std::ostream& o, const localisation::TLocalisationUpdate& u, const TFrameEval& f, const CKeyframeMap& map,
	const TFramesColumns& cols)
{
	o << u.frame << ',' << std::setprecision(6) << u.timestamp << ',' << std::setprecision(3) << u.distance_m << ','
	  << int(f.in_map);
	fixColumns(o, u, map, cols);
	channelColumns(o, u, cols);
	o << ',' << int(u.global_search) << ',';
	if (u.global_search)
		o << u.place.inliers << ',' << u.place.runner_up_inliers;
	else
		o << ',';
	o << ',' << u.frames_since_fix << ',' << u.motion_from;
	if (cols.gt) truthColumns(o, f);
	if (cols.oracle)
		for (size_t c = 0; c < cols.localisers.size(); c++)
			o << ',' << (c < u.oracle.size() && u.oracle[c] >= 0 ? std::to_string(int(u.oracle[c])) : std::string());
	o << '\n';
}
}  // namespace

void writeFramesCsv(const std::string& path, const Updates& ups, const TEvaluation& ev, const CKeyframeMap& map)
{
	const TFramesColumns cols(ups, ev);
	io::CsvWriter csv(path, cols.header());
	csv.out() << std::fixed;
	for (size_t i = 0; i < ups.size(); i++) frameRow(csv.out(), ups[i], ev.frames[i], map, cols);
	csv.commit();
}

void writeSolvesCsv(const std::string& path, const Updates& ups, const TEvaluation& ev)
{
	io::CsvWriter csv(
		path,
		"frame,channel,status,kf_id,matches,warped,patch_matches,inliers,rms_px,var_factor,sigma_m,sigma_deg,prediction_d2,motion_d2,"
		"consistent,track_confirmed,used,err_m,err_deg,nees");
	auto& o = csv.out();
	o << std::fixed;
	for (size_t i = 0; i < ups.size(); i++)
	{
		const auto& u = ups[i];
		const auto& f = ev.frames[i];
		for (size_t c = 0; c < u.localisers.size(); c++)
		{
			const auto& r = u.localisers[c];
			if (!r.solved) continue;
			o << u.frame << ',' << r.channel << ',' << toString(r.status) << ',' << r.kf_id << ',' << r.matches << ','
			  << r.warped << ',' << r.patch_matches << ',' << r.inliers << ',' << std::setprecision(3) << r.rms_px << ',' << r.var_factor << ',' << std::setprecision(5)
			  << r.sigma_m << ',' << r.sigma_deg << ',' << std::setprecision(3) << r.prediction_d2 << ',' << r.motion_d2
			  << ',' << r.consistent << ',' << int(u.track_confirmed) << ',' << int(u.used == r.channel) << ',';
			if (c < f.solve_err_m.size() && f.solve_err_m[c] >= 0)
				o << std::setprecision(4) << f.solve_err_m[c] << ',' << f.solve_err_deg[c] << ',' << std::setprecision(3)
				  << f.solve_nees[c];
			else
				o << ",,";
			o << '\n';
		}
	}
	csv.commit();
}

void writeTrajectory(const std::string& path, const Updates& ups)
{
	io::Trajectory traj;
	for (const auto& u : ups)
		if (u.placeKnown) traj.push_back({u.timestamp, u.T_map_live});
	io::writeTum(path, traj, "live left camera in the map frame (shadyloc localise)");
}

namespace
{
/** summary.json's oracle bound (Oracle.h) inside "ground_truth": in-map
 * frames with a true single-shot fix by either localiser and each one's share. */
Json oracleJson(const TEvaluation& ev, const localisation::TSystemOptions& sys)
{
	auto share = [&](size_t k) { return ev.in_map_frames ? double(k) / double(ev.in_map_frames) : 0.0; };
	Json o = {{"any_in_map", ev.oracle_any_in_map}, {"any_coverage_in_map", fixedNumber(ev.oracle_any_coverage)}};
	for (size_t c = 0; c < ev.oracle_in_map.size() && c < sys.localisers.size(); c++)
		o[sys.localisers[c] + "_coverage_in_map"] = fixedNumber(share(ev.oracle_in_map[c]));
	return o;
}

/** Each localiser's accepted and used fixes (true and false ones with ground truth). */
Json localisersJson(const TEvaluation& ev)
{
	Json list = Json::array();
	for (const auto& s : ev.channels)
	{
		Json c = {{"channel", s.channel}, {"accepted", s.accepted}, {"used", s.used}};
		if (ev.ground_truth)
		{
			const size_t judged = s.true_fixes + s.false_fixes;
			c["true_fixes"] = s.true_fixes;
			c["false_fixes"] = s.false_fixes;
			c["unverifiable"] = s.unverifiable;
			c["false_share"] = fixedNumber(judged ? double(s.false_fixes) / double(judged) : 0.0);
		}
		list.push_back(c);
	}
	return list;
}

/** The fixes against ground truth; null without it. */
Json groundTruthJson(const TEvaluation& ev, const localisation::TSystemOptions& sys)
{
	if (!ev.ground_truth) return nullptr;
	Json g = {{"associated", ev.associated},
			  {"true_fixes", ev.true_fixes},
			  {"true_fixes_in_map", ev.true_fixes_in_map},
			  {"false_fixes", ev.false_fixes},
			  {"unverifiable", ev.unverifiable},
			  {"true_coverage_in_map", fixedNumber(ev.true_coverage_in_map)},
			  {"true_coverage_all", fixedNumber(ev.true_coverage_all)},
			  {"false_fix_share", fixedNumber(ev.false_fix_share)}};
	if (ev.oracle) g["oracle"] = oracleJson(ev, sys);
	return g;
}

/** Distances without a fix and the blind episodes. */
Json blindJson(const TEvaluation& ev)
{
	Json episodes = Json::array();
	for (const auto& e : ev.episodes)
		episodes.push_back(
			{{"first", e.first}, {"last", e.last}, {"length_m", fixedNumber(e.length_m, 3)}, {"kind", toString(e.kind)}});
	return {{"distance_from", ev.ground_truth ? "ground truth" : "VO"},
			{"total_m", fixedNumber(ev.total_m, 3)},
			{"blind_m", fixedNumber(ev.blind_m, 3)},
			{"blind_m_per_km", fixedNumber(ev.blind_m_per_km, 3)},
			{"episodes_between_fixes", ev.episodes_between},
			{"episodes_reaching_m", fixedNumber(TEvalOptions().blind_long_m, 1)},
			{"episodes_long", ev.episodes_long},
			{"p_long", fixedNumber(ev.p_long)},
			{"p_long_ci95_exact", {fixedNumber(ev.p_long_exact_lo), fixedNumber(ev.p_long_exact_hi)}},
			{"p_long_ci95", {fixedNumber(ev.p_long_lo), fixedNumber(ev.p_long_hi)}},
			{"first_fix_frame", ev.first_fix_frame},
			{"before_first_fix_m", fixedNumber(ev.before_first_fix_m, 3)},
			{"episodes", episodes}};
}

/** What the run was made from, each input with its fingerprint. */
Json provenanceJson(const localisation::TSystemOptions& sys, const TLocaliseProvenance& prov)
{
	std::string locList;
	for (const auto& l : sys.localisers) locList += (locList.empty() ? "" : ",") + l;
	const auto hashOf = [](const std::string& given, const std::string& path) {
		return given.empty() ? io::fnv1a64File(path) : given;
	};
	Json p = {{"program", prov.program},
			  {"build_commit", prov.buildCommit},
			  {"localisers", locList},
			  {"start_kf", prov.startKf},
			  {"config", prov.configWhat},
			  {"config_fnv1a64", io::fnv1a64(prov.configText)},
			  {"map", prov.mapPath},
			  {"map_fnv1a64", hashOf(prov.mapHash, prov.mapPath)},
			  {"live", prov.livePath},
			  {"live_fnv1a64", hashOf(prov.liveHash, prov.livePath)}};
	if (!prov.gtPath.empty())
	{
		p["gt"] = prov.gtPath;
		p["gt_fnv1a64"] = hashOf(prov.gtHash, prov.gtPath);
	}
	if (prov.live)
		p["live_capture"] = {
			{"frames_read", prov.liveFramesRead},
			{"frames_dropped", prov.liveFramesDropped},
			{"drops_when_behind", prov.liveDropsWhenBehind}};
	return p;
}

/** Median and 95th percentile of times [ms], 3 decimals. */
Json timesJson(const std::vector<double>& ms, bool p95 = true)
{
	Json t = {{"median", fixedNumber(percentile(ms, 0.5), 3)}};
	if (p95) t["p95"] = fixedNumber(percentile(ms, 0.95), 3);
	return t;
}
}  // namespace

std::string summaryJson(
	const Updates& ups, const TEvaluation& ev, const localisation::TSystemOptions& sys, const TLocaliseProvenance& prov)
{
	// Steps the fallback VO measured where the VO channel's could not.
	size_t fallbackSteps = 0;
	for (const auto& u : ups) fallbackSteps += !u.motion_from.empty() && u.motion_from != sys.vo_channel;
	const Json doc = {{"format", "shadyloc localise summary"},
					  {"version", kSummaryVersion},
					  {"frames", ups.size()},
					  {"in_map_frames", ev.in_map_frames},
					  {"in_map_from", ev.ground_truth ? "ground truth" : "own estimate"},
					  {"fixes", ev.fixes},
					  {"fixes_in_map", ev.fixes_in_map},
					  {"coverage_in_map", fixedNumber(ev.coverage_in_map)},
					  {"coverage_all", fixedNumber(ev.coverage_all)},
					  {"vo", {{"channel", sys.vo_channel}, {"fallback_steps", fallbackSteps}}},
					  {"localisers", localisersJson(ev)},
					  {"ground_truth", groundTruthJson(ev, sys)},
					  {"blind", blindJson(ev)},
					  {"global_searches", ev.global_searches},
					  {"provenance", provenanceJson(sys, prov)}};
	return writeJson(doc, {""});
}

std::string timingJson(const Updates& ups, int threads)
{
	std::vector<double> total, vo;
	std::vector<std::vector<double>> perLoc(ups.empty() ? 0 : ups.front().localisers.size());
	for (const auto& u : ups)
	{
		total.push_back(u.ms_total);
		vo.push_back(u.vo.ms.total);
		for (size_t c = 0; c < u.localisers.size() && c < perLoc.size(); c++) perLoc[c].push_back(u.localisers[c].ms);
	}
	Json localisers = Json::object();
	for (size_t c = 0; c < perLoc.size(); c++) localisers[ups.front().localisers[c].channel] = timesJson(perLoc[c]);
	const Json doc = {{"format", "shadyloc localise timing"},
					  {"version", 1},
					  {"threads", threads},
					  {"frames", ups.size()},
					  {"ms_per_frame", timesJson(total)},
					  {"vo_ms", timesJson(vo, false)},
					  {"localiser_ms", localisers}};
	return writeJson(doc, {""});
}

std::string localiseProvenance(const std::string& dir, const std::string& key)
{
	const Json doc = readJsonFile((std::filesystem::path(dir) / "summary.json").string());
	const Json* p = doc.is_object() && doc.contains("provenance") ? &doc["provenance"] : nullptr;
	return p && p->is_object() && p->contains(key) && (*p)[key].is_string() ? (*p)[key].get<std::string>() : "";
}

void writeLocaliseOutputs(
	const std::string& dir, const Updates& ups, const TEvaluation& ev, const CKeyframeMap& map,
	const localisation::TSystemOptions& sys, const TLocaliseProvenance& prov)
{
	const auto file = [&](const char* name) { return (std::filesystem::path(dir) / name).string(); };
	writeFramesCsv(file("frames.csv"), ups, ev, map);
	writeSolvesCsv(file("solves.csv"), ups, ev);
	writeTrajectory(file("trajectory.tum"), ups);
	io::writeTextFile(file("summary.json"), summaryJson(ups, ev, sys, prov));
	io::writeTextFile(file("timing.json"), timingJson(ups, sys.threads));
}

}  // namespace shadyloc::eval
