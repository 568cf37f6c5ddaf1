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

void writeFramesCsv(const std::string& path, const Updates& ups, const TEvaluation& ev, const CKeyframeMap& map)
{
	const bool gt = ev.ground_truth;
	const std::vector<std::string> named = {"mono", "invariant"};
	std::vector<std::string> extra;	 // localisers with other names
	for (const auto& r : ups.front().localisers)
		if (std::find(named.begin(), named.end(), r.channel) == named.end()) extra.push_back(r.channel);
	std::vector<std::string> perChannel = named;
	perChannel.insert(perChannel.end(), extra.begin(), extra.end());
	std::string header =
		"frame,stamp,distance_m,in_map,mono_ok,invariant_ok,used,kf_run,kf_frame,kf_id,kf_stamp,mono_inliers,"
		"invariant_inliers,rel_x,rel_y,rel_z,rel_qx,rel_qy,rel_qz,rel_qw";
	for (const auto& e : extra) header += "," + e + "_ok," + e + "_inliers";
	for (const auto& c : perChannel)
		for (const char* f : {"status", "matches", "gate_px", "sigma_m", "kf_id", "rel_x", "rel_y", "rel_z", "rel_qx", "rel_qy", "rel_qz", "rel_qw"})
			header += "," + c + "_" + f;
	header += ",global_search,global_inliers,global_runner_up,frames_since_fix,vo_from";
	if (gt) header += ",gt_distance_m,used_true,used_err_m,used_err_deg";
	const bool oracle = !ups.front().oracle.empty();
	if (oracle)
		for (const auto& r : ups.front().localisers) header += "," + r.channel + "_oracle";
	io::CsvWriter csv(path, header);
	auto& o = csv.out();
	o << std::fixed;
	for (size_t i = 0; i < ups.size(); i++)
	{
		const auto& u = ups[i];
		const auto& f = ev.frames[i];
		o << u.frame << ',' << std::setprecision(6) << u.timestamp << ',' << std::setprecision(3) << u.distance_m << ','
		  << int(f.in_map);
		auto okOf = [&](const std::string& c) {
			const auto* r = u.result(c);
			return r ? std::to_string(int(r->accepted())) : std::string();
		};
		auto inlOf = [&](const std::string& c) {
			const auto* r = u.result(c);
			return r ? std::to_string(r->inliers) : std::string();
		};
		o << ',' << okOf("mono") << ',' << okOf("invariant") << ',' << (u.localised() ? u.used : "none");
		if (u.localised())
			o << ',' << map.runs().at(u.kf_run) << ',' << u.kf_frame << ',' << u.kf_id << ',' << std::setprecision(6)
			  << u.kf_stamp;
		else
			o << ",,,,";
		o << ',' << inlOf("mono") << ',' << inlOf("invariant") << ',';
		if (u.localised())
			poseFields(o, u.T_kf_live);
		else
			o << ",,,,,,";
		for (const auto& e : extra) o << ',' << okOf(e) << ',' << inlOf(e);
		for (const auto& c : perChannel)
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
		o << ',' << int(u.global_search) << ',';
		if (u.global_search)
			o << u.place.inliers << ',' << u.place.runner_up_inliers;
		else
			o << ',';
		o << ',' << u.frames_since_fix << ',' << u.motion_from;
		if (gt)
		{
			o << ',' << std::setprecision(3) << f.distance_m << ','
			  << (f.used == FixTruth::None ? std::string() : std::to_string(int(f.used))) << ',';
			if (f.used_err_m >= 0)
				o << std::setprecision(4) << f.used_err_m << ',' << f.used_err_deg;
			else
				o << ',';
		}
		if (oracle)
			for (size_t c = 0; c < ups.front().localisers.size(); c++)
				o << ',' << (c < u.oracle.size() && u.oracle[c] >= 0 ? std::to_string(int(u.oracle[c])) : std::string());
		o << '\n';
	}
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
/** summary.json's oracle bound (Oracle.h) inside "ground_truth", when probed. */
std::string oracleJson(const TEvaluation& ev, const localisation::TSystemOptions& sys)
{
	if (!ev.oracle) return "";
	auto share = [&](size_t k) { return ev.in_map_frames ? double(k) / double(ev.in_map_frames) : 0.0; };
	std::ostringstream js;
	js << ", \"oracle\": {\"any_in_map\": " << ev.oracle_any_in_map << ", \"any_coverage_in_map\": "
	   << jsonNumber(ev.oracle_any_coverage, 6);
	for (size_t c = 0; c < ev.oracle_in_map.size() && c < sys.localisers.size(); c++)
		js << ", " << jsonString(sys.localisers[c] + "_coverage_in_map") << ": " << jsonNumber(share(ev.oracle_in_map[c]), 6);
	js << "}";
	return js.str();
}
}  // namespace

std::string summaryJson(
	const Updates& ups, const TEvaluation& ev, const localisation::TSystemOptions& sys,
	const TLocaliseProvenance& prov)
{
	const bool gt = ev.ground_truth;
	const auto num = [](double v, int prec = 6) { return jsonNumber(v, prec); };
	std::ostringstream js;
	js << "{\n  \"format\": \"shadyloc localise summary\",\n  \"version\": " << kSummaryVersion << ",\n";
	js << "  \"frames\": " << ups.size() << ",\n  \"in_map_frames\": " << ev.in_map_frames
	   << ",\n  \"in_map_from\": " << jsonString(gt ? "ground truth" : "own estimate") << ",\n  \"fixes\": " << ev.fixes
	   << ",\n  \"fixes_in_map\": " << ev.fixes_in_map << ",\n  \"coverage_in_map\": " << num(ev.coverage_in_map)
	   << ",\n  \"coverage_all\": " << num(ev.coverage_all) << ",\n";
	// Steps the fallback VO measured where the VO channel's could not.
	size_t fallbackSteps = 0;
	for (const auto& u : ups) fallbackSteps += !u.motion_from.empty() && u.motion_from != sys.vo_channel;
	js << "  \"vo\": {\"channel\": " << jsonString(sys.vo_channel) << ", \"fallback_steps\": " << fallbackSteps
	   << "},\n";
	js << "  \"localisers\": [";
	for (size_t c = 0; c < ev.channels.size(); c++)
	{
		const auto& s = ev.channels[c];
		js << (c ? ", " : "") << "{\"channel\": " << jsonString(s.channel) << ", \"accepted\": " << s.accepted
		   << ", \"used\": " << s.used;
		if (gt)
			js << ", \"true_fixes\": " << s.true_fixes << ", \"false_fixes\": " << s.false_fixes
			   << ", \"unverifiable\": " << s.unverifiable << ", \"false_share\": "
			   << num(s.true_fixes + s.false_fixes ? double(s.false_fixes) / double(s.true_fixes + s.false_fixes) : 0.0);
		js << "}";
	}
	js << "],\n";
	if (gt)
		js << "  \"ground_truth\": {\"associated\": " << ev.associated << ", \"true_fixes\": " << ev.true_fixes
		   << ", \"true_fixes_in_map\": " << ev.true_fixes_in_map << ", \"false_fixes\": " << ev.false_fixes
		   << ", \"unverifiable\": " << ev.unverifiable << ", \"true_coverage_in_map\": " << num(ev.true_coverage_in_map)
		   << ", \"true_coverage_all\": " << num(ev.true_coverage_all) << ", \"false_fix_share\": "
		   << num(ev.false_fix_share) << oracleJson(ev, sys) << "},\n";
	else
		js << "  \"ground_truth\": null,\n";
	js << "  \"blind\": {\"distance_from\": " << jsonString(gt ? "ground truth" : "VO") << ", \"total_m\": "
	   << num(ev.total_m, 3) << ", \"blind_m\": " << num(ev.blind_m, 3) << ", \"blind_m_per_km\": "
	   << num(ev.blind_m_per_km, 3) << ", \"episodes_between_fixes\": " << ev.episodes_between
	   << ", \"episodes_reaching_m\": " << num(TEvalOptions().blind_long_m, 1) << ", \"episodes_long\": "
	   << ev.episodes_long << ", \"p_long\": " << num(ev.p_long) << ", \"p_long_ci95_exact\": ["
	   << num(ev.p_long_exact_lo) << ", " << num(ev.p_long_exact_hi) << "], \"p_long_ci95\": [" << num(ev.p_long_lo)
	   << ", " << num(ev.p_long_hi) << "], \"first_fix_frame\": " << ev.first_fix_frame << ", \"before_first_fix_m\": "
	   << num(ev.before_first_fix_m, 3) << ", \"episodes\": [";
	for (size_t i = 0; i < ev.episodes.size(); i++)
	{
		const auto& e = ev.episodes[i];
		js << (i ? ", " : "") << "{\"first\": " << e.first << ", \"last\": " << e.last << ", \"length_m\": "
		   << num(e.length_m, 3) << ", \"kind\": "
		   << jsonString(
				  e.kind == TBlindEpisode::Between ? "between" : (e.kind == TBlindEpisode::AtEnd ? "at_end" : "before_first_fix"))
		   << "}";
	}
	js << "]},\n  \"global_searches\": " << ev.global_searches << ",\n";
	std::string locList;
	for (const auto& l : sys.localisers) locList += (locList.empty() ? "" : ",") + l;
	const auto hashOf = [](const std::string& given, const std::string& path) {
		return given.empty() ? io::fnv1a64File(path) : given;
	};
	js << "  \"provenance\": {\"program\": " << jsonString(prov.program) << ", \"build_commit\": "
	   << jsonString(prov.buildCommit) << ", \"localisers\": " << jsonString(locList)
	   << ", \"start_kf\": " << prov.startKf << ", \"config\": " << jsonString(prov.configWhat)
	   << ", \"config_fnv1a64\": " << jsonString(io::fnv1a64(prov.configText)) << ", \"map\": " << jsonString(prov.mapPath)
	   << ", \"map_fnv1a64\": " << jsonString(hashOf(prov.mapHash, prov.mapPath))
	   << ", \"live\": " << jsonString(prov.livePath)
	   << ", \"live_fnv1a64\": " << jsonString(hashOf(prov.liveHash, prov.livePath));
	if (!prov.gtPath.empty())
		js << ", \"gt\": " << jsonString(prov.gtPath) << ", \"gt_fnv1a64\": " << jsonString(hashOf(prov.gtHash, prov.gtPath));
	js << "}\n}\n";
	return js.str();
}

std::string timingJson(const Updates& ups, int threads)
{
	const auto num = [](double v, int prec) { return jsonNumber(v, prec); };
	std::vector<double> tot;
	std::vector<std::vector<double>> perLoc(ups.empty() ? 0 : ups.front().localisers.size());
	std::vector<double> voMs;
	for (const auto& u : ups)
	{
		tot.push_back(u.ms_total);
		voMs.push_back(u.vo.ms.total);
		for (size_t c = 0; c < u.localisers.size() && c < perLoc.size(); c++) perLoc[c].push_back(u.localisers[c].ms);
	}
	std::ostringstream tj;
	tj << "{\n  \"format\": \"shadyloc localise timing\",\n  \"version\": 1,\n  \"threads\": " << threads
	   << ",\n  \"frames\": " << ups.size() << ",\n  \"ms_per_frame\": {\"median\": " << num(percentile(tot, 0.5), 3)
	   << ", \"p95\": " << num(percentile(tot, 0.95), 3) << "},\n  \"vo_ms\": {\"median\": "
	   << num(percentile(voMs, 0.5), 3) << "},\n  \"localiser_ms\": {";
	for (size_t c = 0; c < perLoc.size(); c++)
		tj << (c ? ", " : "") << jsonString(ups.front().localisers[c].channel) << ": {\"median\": "
		   << num(percentile(perLoc[c], 0.5), 3) << ", \"p95\": " << num(percentile(perLoc[c], 0.95), 3) << "}";
	tj << "}\n}\n";
	return tj.str();
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
