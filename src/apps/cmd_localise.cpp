/* shadyloc localise: a live stereo run against a dual-channel keyframe map
 * with the combined system (docs/localisation.md). */
#include "Command.h"
#include "CommandLine.h"

#include <shadyloc/core/Settings.h>
#include <shadyloc/filters/Channel.h>
#include <shadyloc/io/AtomicFile.h>
#include <shadyloc/io/Csv.h>
#include <shadyloc/io/StereoFrameSource.h>
#include <shadyloc/io/Tum.h>
#include <shadyloc/localisation/Evaluation.h>
#include <shadyloc/localisation/LocalisationSystem.h>
#include <shadyloc/vo/VOConfig.h>

#include <mrpt/3rdparty/tclap/CmdLine.h>
#include <mrpt/config/CConfigFileMemory.h>

#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <sstream>

#ifndef SHADYLOC_GIT_COMMIT
#define SHADYLOC_GIT_COMMIT "unknown"
#endif

namespace
{
using namespace shadyloc;
using namespace shadyloc::localisation;
namespace fs = std::filesystem;

/** summary.json's format version (docs/localisation.md). */
constexpr int kSummaryVersion = 1;

std::string slurp(const std::string& path)
{
	std::ifstream f(path, std::ios::binary);
	if (!f) throw std::runtime_error("cannot read '" + path + "'");
	std::ostringstream s;
	s << f.rdbuf();
	return s.str();
}

/** FNV-1a, 64 bit, of a file's bytes: the provenance's input hash. */
std::string fnv1a64File(const std::string& path)
{
	std::ifstream f(path, std::ios::binary);
	if (!f) throw std::runtime_error("cannot read '" + path + "'");
	uint64_t h = 1469598103934665603ull;
	std::vector<char> buf(1 << 16);
	while (f)
	{
		f.read(buf.data(), static_cast<std::streamsize>(buf.size()));
		const auto got = f.gcount();
		for (std::streamsize i = 0; i < got; i++)
		{
			h ^= static_cast<uint8_t>(buf[static_cast<size_t>(i)]);
			h *= 1099511628211ull;
		}
	}
	char s[17];
	std::snprintf(s, sizeof s, "%016llx", static_cast<unsigned long long>(h));
	return s;
}
std::string fnv1a64(const std::string& text)
{
	uint64_t h = 1469598103934665603ull;
	for (const char c : text)
	{
		h ^= static_cast<uint8_t>(c);
		h *= 1099511628211ull;
	}
	char s[17];
	std::snprintf(s, sizeof s, "%016llx", static_cast<unsigned long long>(h));
	return s;
}

std::string jsonString(const std::string& s)
{
	std::string o = "\"";
	for (const char c : s)
	{
		if (c == '"' || c == '\\')
			o += std::string("\\") + c;
		else if (c == '\n')
			o += "\\n";
		else if (static_cast<unsigned char>(c) < 0x20)
		{
			char b[8];
			std::snprintf(b, sizeof b, "\\u%04x", c);
			o += b;
		}
		else
			o += c;
	}
	return o + "\"";
}
std::string num(double v, int prec = 6)
{
	if (!std::isfinite(v)) return "null";
	std::ostringstream s;
	s << std::fixed << std::setprecision(prec) << v;
	return s.str();
}

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

/** A directory filled under a temporary name, renamed into place on commit();
 * removed on destruction otherwise: no partial output. */
class StagedDir
{
   public:
	explicit StagedDir(const std::string& dst) : m_dst(fs::path(dst).lexically_normal())
	{
		if (m_dst.filename().empty()) m_dst = m_dst.parent_path();
		const fs::path parent = m_dst.parent_path().empty() ? fs::path(".") : m_dst.parent_path();
		if (!fs::is_directory(parent))
			throw std::runtime_error("output '" + dst + "': parent directory '" + parent.string() + "' does not exist");
		if (fs::exists(m_dst) && !fs::is_directory(m_dst))
			throw std::runtime_error("output '" + dst + "' exists and is not a directory");
		m_tmp = parent / ("." + m_dst.filename().string() + ".partial-" + std::to_string(::getpid()));
		fs::remove_all(m_tmp);
		fs::create_directory(m_tmp);
	}
	~StagedDir()
	{
		std::error_code ec;
		if (!m_done) fs::remove_all(m_tmp, ec);
	}
	std::string file(const std::string& name) const { return (m_tmp / name).string(); }
	void commit()
	{
		// The files of an earlier run are replaced as a whole.
		fs::path old;
		if (fs::exists(m_dst))
		{
			old = m_tmp;
			old += ".old";
			fs::rename(m_dst, old);
		}
		fs::rename(m_tmp, m_dst);
		m_done = true;
		if (!old.empty()) fs::remove_all(old);
	}

   private:
	fs::path m_dst, m_tmp;
	bool m_done = false;
};

std::vector<std::string> splitList(const std::string& s)
{
	std::vector<std::string> out;
	std::string w;
	for (const char c : s + ",")
		if (c == ',' || c == ' ')
		{
			if (!w.empty()) out.push_back(w);
			w.clear();
		}
		else
			w += c;
	return out;
}

int run(int argc, char** argv)
{
	shadyloc::apps::CommandLine cli(
		"Localises a live stereo run against a dual-channel keyframe map (shadyloc survey) with the combined "
		"system: live VO on the monochrome channel predicts for the localisers (mono, invariant), which run in "
		"parallel; the monochrome fix is used when it succeeds, else the invariant one, else VO dead-reckons. "
		"The run starts by a global search over the map (or at --start-kf). Writes OUTDIR/frames.csv, "
		"trajectory.tum, summary.json and timing.json (docs/localisation.md).");
	auto& cmd = cli.cmd();
	TCLAP::ValueArg<std::string> mapArg("m", "map", "keyframe map (.kfmap)", true, "", "map.kfmap", cmd);
	TCLAP::ValueArg<std::string> in("i", "input", "live rawlog (colour stereo)", true, "", "live.rawlog", cmd);
	TCLAP::ValueArg<std::string> out("o", "output", "output directory (replaced as a whole)", true, "", "OUTDIR", cmd);
	TCLAP::MultiArg<std::string> cfgArgs(
		"c", "config",
		"options .ini, may be repeated (sections of all files together): [localise], [localiser], "
		"[localiser.<channel>], [vo], [features], channel filter sections",
		false, "ini", cmd);
	TCLAP::ValueArg<std::string> gtArg(
		"", "gt", "live run's ground truth (TUM), in the world frame of the map's ground truth", false, "", "live.tum", cmd);
	TCLAP::ValueArg<std::string> locArg(
		"", "localisers", "localisers in policy order (default: [localise] localisers, else mono,invariant)", false, "",
		"mono,invariant", cmd);
	shadyloc::apps::NumberArg<int> threads(
		cli, "", "threads", "threads (default: [localise] threads, else 2)", 0, "N", 0, 64);
	shadyloc::apps::NumberArg<int> startKf(
		cli, "", "start-kf", "start at this map keyframe instead of by global search", -1, "id", -1, 1000000000);
	TCLAP::ValueArg<std::string> label("", "label", "sensor label of the live colour stereo camera", false, "", "label", cmd);
	TCLAP::SwitchArg quiet("q", "quiet", "no progress output", cmd);
	TCLAP::SwitchArg debug(
		"", "debug",
		"per frame and localiser on stderr: keyframe, predicted offset from it, matches, inliers, gate, status", cmd);
	if (const auto rc = cli.parse(argc, argv)) return *rc;
	const bool talk = !quiet.getValue();

	// ---- inputs, checked before any work
	const std::string mapPath = mapArg.getValue(), livePath = in.getValue();
	if (!fs::exists(mapPath)) throw std::runtime_error("map '" + mapPath + "' does not exist");
	if (!fs::exists(livePath)) throw std::runtime_error("live rawlog '" + livePath + "' does not exist");
	std::string cfgText, cfgWhat;
	for (const auto& c : cfgArgs.getValue())
	{
		if (!fs::exists(c)) throw std::runtime_error("config file '" + c + "' does not exist");
		cfgText += slurp(c) + "\n";
		cfgWhat += (cfgWhat.empty() ? "" : " + ") + c;
	}
	if (cfgWhat.empty()) cfgWhat = "(no config)";
	mrpt::config::CConfigFileMemory cfg(cfgText);
	std::optional<io::Trajectory> gt;
	if (gtArg.isSet()) gt = io::readTum(gtArg.getValue());

	CKeyframeMap::Ptr map;
	try
	{
		map = CKeyframeMap::LoadFromFile(mapPath);
	}
	catch (const std::exception& e)
	{
		throw std::runtime_error(std::string("map: ") + e.what());
	}
	if (map->isEmpty()) throw std::runtime_error("map '" + mapPath + "' has no keyframes: nothing to localise against");

	std::vector<std::string> locs;
	if (locArg.isSet())
	{
		locs = splitList(locArg.getValue());
		if (locs.empty()) throw std::runtime_error("--localisers: names no localiser (mono, invariant)");
	}
	std::unique_ptr<CLocalisationSystem> sys;
	try
	{
		std::vector<std::string> known = vo::voConfigSections();
		for (const char* s : {"mono", "invariant", "map", "filters", "localise", "localiser", "localiser.mono", "localiser.invariant"})
			known.push_back(s);
		std::vector<std::string> sections;
		cfg.getAllSections(sections);
		for (const auto& s : sections)
			if (s.rfind("localiser.", 0) == 0 || s.rfind("vo.", 0) == 0 || s.rfind("features.", 0) == 0 ||
				cfg.keyExists(s, "class"))	// per-channel overrides; a channel's filter section
				known.push_back(s);
		core::checkSections(cfg, known, "localise config " + cfgWhat);
		sys = CLocalisationSystem::FromConfig(cfg, map, locs, threads.getValue(), cfgWhat);
	}
	catch (const std::out_of_range& e)
	{
		throw std::runtime_error("map '" + mapPath + "': " + e.what());
	}
	catch (const std::runtime_error& e)
	{
		throw std::runtime_error("map '" + mapPath + "' and config " + cfgWhat + ": " + e.what());
	}
	if (debug.getValue()) sys->setMinLoggingLevel(mrpt::system::LVL_DEBUG);
	if (startKf.isSet())
	{
		if (startKf.getValue() < 0 || static_cast<size_t>(startKf.getValue()) >= map->keyframeCount())
			throw std::runtime_error(
				"--start-kf " + std::to_string(startKf.getValue()) + ": the map has keyframes 0.." +
				std::to_string(map->keyframeCount() - 1));
		sys->setStartKeyframe(static_cast<uint32_t>(startKf.getValue()));
	}

	// ---- the live run's colour stereo pair (each channel is made from it)
	std::vector<std::string> suffixes;
	for (const auto& l : sys->channelLabels()) suffixes.push_back(sys->channelSetup(l).channel.suffix());
	for (const char* s : {"_mono", "_inv", "_lin"}) suffixes.push_back(s);
	io::TStereoFrameSourceOptions so;
	so.sensorLabel = label.getValue();
	if (so.sensorLabel.empty())
	{
		so.sensorLabel = io::findStereoLabel(livePath, io::labelWithoutSuffixes(suffixes));
		if (so.sensorLabel.empty())
		{
			const std::string any = io::findStereoLabel(livePath, [](const std::string&) { return true; });
			throw std::runtime_error(
				"live rawlog '" + livePath + "': no colour stereo observations" +
				(any.empty() ? std::string(" at all") : " (only derived channel images such as '" + any + "')") +
				"; the localisers need the colour images to make their channels (" + [&] {
					std::string s;
					for (const auto& l : sys->channelLabels()) s += (s.empty() ? "" : ", ") + l;
					return s;
				}() + ")");
		}
	}
	io::StereoFrameSource source(livePath, so);
	if (talk)
	{
		std::cout << "map: " << mapPath << " (" << map->keyframeCount() << " keyframes, " << std::fixed
				  << std::setprecision(1) << map->pathLength() << " m)\nlive: " << livePath << " ('" << so.sensorLabel
				  << "')\n[localise]\n";
		sys->options().dump(std::cout);
	}

	std::vector<TLocalisationUpdate> ups;
	io::TStereoFrame fr;
	while (source.next(fr))
	{
		if (fr.left.type() != CV_8UC3)
			throw std::runtime_error(source.reader().where(
				"frame " + std::to_string(fr.index) + ": '" + so.sensorLabel +
				"' is not a colour pair; the invariant channel needs colour images"));
		try
		{
			ups.push_back(sys->processFrame(fr.left, fr.right, fr.calib, fr.timestamp));
		}
		catch (const std::exception& e)
		{
			throw std::runtime_error(source.reader().where(e.what()));
		}
		const auto& u = ups.back();
		if (talk && (u.frame % 50 == 0))
			std::cout << "frame " << u.frame << ": " << (u.localised() ? u.used : std::string("none")) << std::endl;
	}
	if (ups.empty()) throw std::runtime_error(source.noFramesMessage());

	// ---- evaluation
	const TEvaluation ev = evaluate(ups, *map, gt ? &*gt : nullptr);

	// ---- outputs, all or nothing
	StagedDir dir(out.getValue());
	const std::vector<std::string> named = {"mono", "invariant"};
	std::vector<std::string> extra;	 // localisers with other names
	for (const auto& r : ups.front().localisers)
		if (std::find(named.begin(), named.end(), r.channel) == named.end()) extra.push_back(r.channel);
	std::vector<std::string> perChannel = named;
	perChannel.insert(perChannel.end(), extra.begin(), extra.end());
	{
		std::string header =
			"frame,stamp,distance_m,in_map,mono_ok,invariant_ok,used,kf_run,kf_frame,kf_id,kf_stamp,mono_inliers,"
			"invariant_inliers,rel_x,rel_y,rel_z,rel_qx,rel_qy,rel_qz,rel_qw";
		for (const auto& e : extra) header += "," + e + "_ok," + e + "_inliers";
		for (const auto& c : perChannel)
			for (const char* f : {"status", "matches", "gate_px", "sigma_m", "kf_id", "rel_x", "rel_y", "rel_z", "rel_qx", "rel_qy", "rel_qz", "rel_qw"})
				header += "," + c + "_" + f;
		header += ",global_search,global_inliers,global_runner_up,frames_since_fix";
		if (gt) header += ",gt_distance_m,used_true,used_err_m,used_err_deg";
		io::CsvWriter csv(dir.file("frames.csv"), header);
		auto& o = csv.out();
		o << std::fixed;
		for (size_t i = 0; i < ups.size(); i++)
		{
			const auto& u = ups[i];
			const auto& f = ev.frames[i];
			o << u.frame << ',' << std::setprecision(6) << u.timestamp << ',' << std::setprecision(3) << u.distance_m
			  << ',' << int(f.in_map);
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
				o << ',' << map->runs().at(u.kf_run) << ',' << u.kf_frame << ',' << u.kf_id << ',' << std::setprecision(6)
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
			if (u.global_search) o << u.place.inliers << ',' << u.place.runner_up_inliers;
			else o << ',';
			o << ',' << u.frames_since_fix;
			if (gt)
			{
				o << ',' << std::setprecision(3) << f.distance_m << ','
				  << (f.used == FixTruth::None ? std::string() : std::to_string(int(f.used))) << ',';
				if (f.used_err_m >= 0) o << std::setprecision(4) << f.used_err_m << ',' << f.used_err_deg;
				else o << ',';
			}
			o << '\n';
		}
		csv.commit();
	}
	io::Trajectory traj;
	for (const auto& u : ups)
		if (u.placeKnown) traj.push_back({u.timestamp, u.T_map_live});
	io::writeTum(dir.file("trajectory.tum"), traj, "live left camera in the map frame (shadyloc localise)");

	std::ostringstream js;
	js << "{\n  \"format\": \"shadyloc localise summary\",\n  \"version\": " << kSummaryVersion << ",\n";
	js << "  \"frames\": " << ups.size() << ",\n  \"in_map_frames\": " << ev.in_map_frames
	   << ",\n  \"in_map_from\": " << jsonString(gt ? "ground truth" : "own estimate") << ",\n  \"fixes\": " << ev.fixes
	   << ",\n  \"fixes_in_map\": " << ev.fixes_in_map << ",\n  \"coverage_in_map\": " << num(ev.coverage_in_map)
	   << ",\n  \"coverage_all\": " << num(ev.coverage_all) << ",\n";
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
		   << num(ev.false_fix_share) << "},\n";
	else
		js << "  \"ground_truth\": null,\n";
	js << "  \"blind\": {\"distance_from\": " << jsonString(gt ? "ground truth" : "VO") << ", \"total_m\": "
	   << num(ev.total_m, 3) << ", \"blind_m\": " << num(ev.blind_m, 3) << ", \"blind_m_per_km\": "
	   << num(ev.blind_m_per_km, 3) << ", \"episodes_between_fixes\": " << ev.episodes_between
	   << ", \"episodes_reaching_m\": " << num(TEvalOptions().blind_long_m, 1) << ", \"episodes_long\": "
	   << ev.episodes_long << ", \"p_long\": " << num(ev.p_long) << ", \"p_long_ci95\": [" << num(ev.p_long_lo) << ", "
	   << num(ev.p_long_hi) << "], \"first_fix_frame\": " << ev.first_fix_frame << ", \"before_first_fix_m\": "
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
	for (const auto& l : sys->options().localisers) locList += (locList.empty() ? "" : ",") + l;
	js << "  \"provenance\": {\"program\": \"shadyloc localise\", \"build_commit\": " << jsonString(SHADYLOC_GIT_COMMIT)
	   << ", \"localisers\": " << jsonString(locList) << ", \"start_kf\": " << startKf.getValue()
	   << ", \"config\": " << jsonString(cfgWhat) << ", \"config_fnv1a64\": " << jsonString(fnv1a64(cfgText))
	   << ", \"map\": " << jsonString(mapPath) << ", \"map_fnv1a64\": " << jsonString(fnv1a64File(mapPath))
	   << ", \"live\": " << jsonString(livePath) << ", \"live_fnv1a64\": " << jsonString(fnv1a64File(livePath));
	if (gt)
		js << ", \"gt\": " << jsonString(gtArg.getValue()) << ", \"gt_fnv1a64\": " << jsonString(fnv1a64File(gtArg.getValue()));
	js << "}\n}\n";
	io::writeAtomically(dir.file("summary.json"), [&](const std::string& p) {
		std::ofstream f(p);
		f << js.str();
		if (!f) throw std::runtime_error("cannot write '" + p + "'");
	});

	std::vector<double> tot;
	std::vector<std::vector<double>> perLoc(ups.front().localisers.size());
	std::vector<double> voMs;
	for (const auto& u : ups)
	{
		tot.push_back(u.ms_total);
		voMs.push_back(u.vo.ms.total);
		for (size_t c = 0; c < u.localisers.size() && c < perLoc.size(); c++) perLoc[c].push_back(u.localisers[c].ms);
	}
	std::ostringstream tj;
	tj << "{\n  \"format\": \"shadyloc localise timing\",\n  \"version\": 1,\n  \"threads\": " << sys->options().threads
	   << ",\n  \"frames\": " << ups.size() << ",\n  \"ms_per_frame\": {\"median\": " << num(percentile(tot, 0.5), 3)
	   << ", \"p95\": " << num(percentile(tot, 0.95), 3) << "},\n  \"vo_ms\": {\"median\": "
	   << num(percentile(voMs, 0.5), 3) << "},\n  \"localiser_ms\": {";
	for (size_t c = 0; c < perLoc.size(); c++)
		tj << (c ? ", " : "") << jsonString(ups.front().localisers[c].channel) << ": {\"median\": "
		   << num(percentile(perLoc[c], 0.5), 3) << ", \"p95\": " << num(percentile(perLoc[c], 0.95), 3) << "}";
	tj << "}\n}\n";
	io::writeAtomically(dir.file("timing.json"), [&](const std::string& p) {
		std::ofstream f(p);
		f << tj.str();
		if (!f) throw std::runtime_error("cannot write '" + p + "'");
	});
	dir.commit();

	std::cout << std::fixed << std::setprecision(1) << "frames " << ups.size() << ", in map " << ev.in_map_frames
			  << ", fixes " << ev.fixes << ": coverage " << 100 * ev.coverage_in_map << " % of in-map frames ("
			  << 100 * ev.coverage_all << " % of all)";
	for (const auto& s : ev.channels) std::cout << "; " << s.channel << " " << s.accepted << " (used " << s.used << ")";
	std::cout << "\n";
	if (gt)
		std::cout << "ground truth: true coverage " << 100 * ev.true_coverage_in_map << " % (self-reported "
				  << 100 * ev.coverage_in_map << " %), false fixes " << ev.false_fixes << " (" << std::setprecision(2)
				  << 100 * ev.false_fix_share << " %)\n";
	std::cout << std::setprecision(1) << "blind: " << ev.blind_m << " m of " << ev.total_m << " m, first fix at frame "
			  << ev.first_fix_frame << "; -> " << out.getValue() << "\n";
	return 0;
}

shadyloc::apps::RegisterCommand reg(
	"localise",
	{"a live run against a keyframe map, combined system (-m MAP -i live.rawlog -o OUTDIR [-c ini] [--gt live.tum] "
	 "[--localisers mono,invariant])",
	 run});
}  // namespace
