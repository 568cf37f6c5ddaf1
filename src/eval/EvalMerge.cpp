/* ShadyLoc — the leave-one-out evaluation's merge: the jobs' records into
 * Table I, the ground-truth summaries, the pooled blind distances and
 * eval.json (docs/evaluation.md). Deterministic: the same job records give
 * the same bytes, whichever way the jobs ran. */
#include <shadyloc/eval/Figures.h>
#include <shadyloc/eval/LeaveOneOut.h>
#include <shadyloc/io/OutputTransaction.h>
#include <shadyloc/eval/Evaluation.h>
#include <shadyloc/io/FileHash.h>
#include <shadyloc/map/CKeyframeMap.h>

#include "EvalRecords.h"
#include "Json.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <limits>
#include <map>
#include <regex>
#include <sstream>

namespace shadyloc::eval
{
namespace fs = std::filesystem;

namespace
{
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
const char* const kPairFiles[] = {"frames.csv", "summary.json", "trajectory.tum"};

double ratio(size_t a, size_t b) { return b ? static_cast<double>(a) / static_cast<double>(b) : kNaN; }
/** The exact 95 % upper bound (Clopper-Pearson) of a false share: what the
 * localisation issue's "under 0.1 %" is judged by (NaN without fixes). */
double falseShareUpper(size_t falseFixes, size_t fixes)
{
	return fixes ? clopperPearson(falseFixes, fixes, 0.95).hi : kNaN;
}

/** Mean of the finite values; NaN if none. */
double meanOf(const std::vector<double>& v)
{
	double s = 0;
	size_t n = 0;
	for (const double x : v)
		if (std::isfinite(x))
		{
			s += x;
			n++;
		}
	return n ? s / static_cast<double>(n) : kNaN;
}

/** Nearest-rank percentile (as localise's timing); NaN if empty. */
double percentile(std::vector<double> v, double p)
{
	if (v.empty()) return kNaN;
	std::sort(v.begin(), v.end());
	return v[static_cast<size_t>(std::round(p * static_cast<double>(v.size() - 1)))];
}

std::string pct(double v, int prec = 2)
{
	if (!std::isfinite(v)) return "n/a";
	std::ostringstream s;
	s << std::fixed << std::setprecision(prec) << 100 * v;
	return s.str();
}
std::string csvPct(double v) { return std::isfinite(v) ? pct(v, 4) : std::string(); }

std::string pairDirName(const TEvalJob& j, const std::vector<TRun>& runs)
{
	return runs[j.run].name + "__" + runs[j.map].name + "__" + toString(j.system);
}

/** One Table I row: per live run, averaged over the maps. */
struct TRow
{
	std::string live;
	size_t maps = 0;
	bool truth = false;	 //!< every pair of the row has ground truth
	double base = kNaN, inv = kNaN, comb = kNaN;  //!< true coverage [0..1]
	double baseSelf = kNaN, invSelf = kNaN, combSelf = kNaN;  //!< self-reported [0..1]
};

/** A system's numbers pooled over its pairs. */
struct TPooled
{
	size_t pairs = 0, gtPairs = 0;
	std::map<std::string, TPairChannel> channels;  //!< over pairs with ground truth
	std::vector<std::string> channelOrder;
	size_t trueFixes = 0, falseFixes = 0, unverifiable = 0;	 //!< the fixes used, pairs with ground truth
	std::vector<double> errM, errDeg;
	size_t binFrames = 0;
	std::array<size_t, 3> bins = {0, 0, 0};
	std::vector<double> between;  //!< blind episodes between fixes [m], all pairs
	size_t atEnd = 0, beforeFirst = 0, neverLocalised = 0;
	double blindM = 0, totalM = 0;
};

std::string readJobWall(const std::string& path)
{
	std::ifstream f(path);
	std::stringstream s;
	s << f.rdbuf();
	static const std::regex re(R"("wall_s": ([0-9.eE+-]+|null))");
	std::smatch m;
	const std::string t = s.str();
	return std::regex_search(t, m, re) ? std::string(m[1]) : std::string("null");
}

/** "" if the map job's map loads (every block's checksum) and holds the
 * keyframes its record counts; else why not. The merge publishes the map
 * and its hash: a damaged one would go out as the evaluation's. */
std::string checkMapFile(const std::string& path, const TMapRecord& rec)
{
	const auto m = CKeyframeMap::LoadFromFile(path);
	if (m->keyframeCount() != rec.keyframes)
		return "'" + path + "' holds " + std::to_string(m->keyframeCount()) + " keyframes, its record map.tsv " +
			   std::to_string(rec.keyframes) + " (a map replaced after its job ran)";
	return "";
}
}  // namespace

TMergeResult merge(const std::string& outDir, const TEvalInputs& in, const std::vector<TEvalJob>& jobs, double wall_s)
{
	const auto& runs = in.runs;
	const size_t n = runs.size();
	const fs::path out(outDir);
	// ---- every job's record, or a list of what is missing
	std::vector<TMapRecord> maps(n);
	std::vector<TPairRecord> pairs(jobs.size());
	std::string missing;
	size_t nMissing = 0;
	for (const auto& j : jobs)
	{
		const fs::path dir = out / "jobs" / j.name;
		std::string why;
		try
		{
			if (!fs::is_directory(dir))
				why = "no output ('" + dir.string() + "')";
			else if (j.isMap)
			{
				if (!fs::exists(dir / "map.kfmap")) why = "no map.kfmap in '" + dir.string() + "'";
				else
				{
					maps[j.run] = readMapRecord((dir / "map.tsv").string());
					why = checkMapFile((dir / "map.kfmap").string(), maps[j.run]);
				}
			}
			else
			{
				for (const char* f : kPairFiles)
					if (why.empty() && !fs::is_regular_file(dir / f)) why = "no " + std::string(f) + " in '" + dir.string() + "'";
				if (why.empty())
				{
					pairs[j.index] = readPairRecord((dir / "pair.tsv").string());
					const auto& p = pairs[j.index];
					if (p.live != runs[j.run].name || p.map != runs[j.map].name || p.system != toString(j.system))
						why = "'" + (dir / "pair.tsv").string() + "' is of pair " + p.live + "/" + p.map + "/" + p.system;
				}
			}
		}
		catch (const std::exception& e)
		{
			why = e.what();
		}
		if (why.empty()) continue;
		nMissing++;
		std::string what = j.isMap ? "map of run '" + runs[j.run].name + "'"
								   : "live run '" + runs[j.run].name + "' against the map of '" + runs[j.map].name +
										 "', " + toString(j.system);
		missing += "\n  job " + std::to_string(j.index) + " (" + what + "): " + why;
	}
	if (nMissing)
		throw std::runtime_error(
			"cannot merge: " + std::to_string(nMissing) + " of " + std::to_string(jobs.size()) +
			" jobs have no usable output in '" + (out / "jobs").string() + "':" + missing +
			"\nrun them (shadyloc eval --runs " + in.runsPath + " -o " + outDir + " ... --job K), then merge again");

	// ---- Table I: per live run, averaged over the maps
	std::vector<TRow> rows;
	TPooled pooled[2];
	for (size_t i = 0; i < n; i++)
	{
		TRow row;
		row.live = runs[i].name;
		row.truth = true;
		std::vector<double> b, v, c, bs, vs, cs;
		for (size_t m = 0; m < n; m++)
		{
			if (m == i) continue;
			row.maps++;
			const auto& pb = pairs[pairJobIndex(n, i, m, EvalSystem::Baseline)];
			const auto& pc = pairs[pairJobIndex(n, i, m, EvalSystem::Combined)];
			row.truth &= pb.ground_truth && pc.ground_truth;
			b.push_back(ratio(pb.true_fixes_in_map, pb.in_map_frames));
			c.push_back(ratio(pc.true_fixes_in_map, pc.in_map_frames));
			bs.push_back(ratio(pb.fixes_in_map, pb.in_map_frames));
			cs.push_back(ratio(pc.fixes_in_map, pc.in_map_frames));
			// Invariant alone: the combined run's invariant channel (its own
			// accepted fixes, used or not), docs/evaluation.md.
			const auto* inv = pc.channel("invariant");
			v.push_back(inv ? ratio(inv->true_in_map, pc.in_map_frames) : kNaN);
			vs.push_back(inv ? ratio(inv->accepted_in_map, pc.in_map_frames) : kNaN);
		}
		if (row.truth)
		{
			row.base = meanOf(b);
			row.inv = meanOf(v);
			row.comb = meanOf(c);
		}
		row.baseSelf = meanOf(bs);
		row.invSelf = meanOf(vs);
		row.combSelf = meanOf(cs);
		rows.push_back(row);
	}
	TRow mean;
	mean.live = "mean";
	{
		std::vector<double> b, v, c, bs, vs, cs;
		for (const auto& r : rows)
		{
			b.push_back(r.base);
			v.push_back(r.inv);
			c.push_back(r.comb);
			bs.push_back(r.baseSelf);
			vs.push_back(r.invSelf);
			cs.push_back(r.combSelf);
		}
		mean.base = meanOf(b);
		mean.inv = meanOf(v);
		mean.comb = meanOf(c);
		mean.baseSelf = meanOf(bs);
		mean.invSelf = meanOf(vs);
		mean.combSelf = meanOf(cs);
		mean.maps = n - 1;
	}

	// ---- pooled per system
	for (const auto& j : jobs)
	{
		if (j.isMap) continue;
		const auto& p = pairs[j.index];
		auto& P = pooled[j.system == EvalSystem::Combined];
		P.pairs++;
		for (const auto& e : p.episodes)
		{
			if (e.first == "between") P.between.push_back(e.second);
			else if (e.first == "at_end") P.atEnd++;
			else P.beforeFirst++;
		}
		P.neverLocalised += p.first_fix_frame < 0;
		P.blindM += p.blind_m;
		P.totalM += p.total_m;
		if (!p.ground_truth) continue;
		P.gtPairs++;
		for (const auto& c : p.channels)
		{
			if (!P.channels.count(c.name)) P.channelOrder.push_back(c.name);
			auto& C = P.channels[c.name];
			C.name = c.name;
			C.accepted += c.accepted;
			C.true_fixes += c.true_fixes;
			C.false_fixes += c.false_fixes;
			C.unverifiable += c.unverifiable;
		}
		P.trueFixes += p.true_fixes;
		P.falseFixes += p.false_fixes;
		P.unverifiable += p.unverifiable;
		for (const auto& e : p.fix_errors)
		{
			P.errM.push_back(e[0]);
			P.errDeg.push_back(e[1]);
		}
		P.binFrames += p.in_map_frames;
		for (size_t b = 0; b < 3; b++) P.bins[b] += p.bins[b];
	}
	const TEvalOptions evo;
	TBlindProbability bp[2];
	for (int s = 0; s < 2; s++) bp[s] = blindProbability(pooled[s].between, evo);
	const bool anyGt = pooled[0].gtPairs + pooled[1].gtPairs > 0;
	const char* sysName[2] = {"baseline", "combined"};

	// ---- table1.md / table1.csv
	std::ostringstream md, csv;
	md << "# Table I: coverage, leave-one-out\n\n"
	   << "Each live run localised against the map of every other run (" << n - 1
	   << " maps), averaged over the maps: the share of in-map frames with a fix [%]. True coverage counts fixes "
		  "within 0.5 m and 2 deg of the ground truth; self-reported counts every fix. Invariant alone is the "
		  "combined run's invariant localiser (docs/evaluation.md).\n\n"
	   << "| live run | maps | baseline | invariant alone | combined | self-reported: baseline | invariant alone | "
		  "combined |\n|---|---|---|---|---|---|---|---|\n";
	csv << "live,maps,baseline_pct,invariant_pct,combined_pct,baseline_self_pct,invariant_self_pct,combined_self_pct\n";
	for (const auto* r : [&] {
			 std::vector<const TRow*> all;
			 for (const auto& x : rows) all.push_back(&x);
			 all.push_back(&mean);
			 return all;
		 }())
	{
		const bool isMean = r == &mean;
		md << "| " << (isMean ? "**mean**" : r->live) << " | " << r->maps << " | " << pct(r->base) << " | "
		   << pct(r->inv) << " | " << pct(r->comb) << " | " << pct(r->baseSelf) << " | " << pct(r->invSelf) << " | "
		   << pct(r->combSelf) << " |\n";
		csv << r->live << ',' << r->maps << ',' << csvPct(r->base) << ',' << csvPct(r->inv) << ',' << csvPct(r->comb)
			<< ',' << csvPct(r->baseSelf) << ',' << csvPct(r->invSelf) << ',' << csvPct(r->combSelf) << '\n';
	}
	if (!anyGt) md << "\nNo run pair has ground truth on both sides: true coverage is n/a.\n";

	// ---- summary.md: ground truth and blind distances
	std::ostringstream sm;
	sm << "# Leave-one-out summary\n\n";
	if (anyGt)
	{
		sm << "## Fixes against ground truth (pairs with ground truth on both sides)\n\n"
		   << "| system | localiser | accepted | true | false | unverifiable | false share [%] | exact 95 % upper "
			  "bound [%] |\n"
		   << "|---|---|---|---|---|---|---|---|\n";
		for (int s = 0; s < 2; s++)
		{
			const auto& P = pooled[s];
			for (const auto& name : P.channelOrder)
			{
				const auto& C = P.channels.at(name);
				sm << "| " << sysName[s] << " | " << name << " | " << C.accepted << " | " << C.true_fixes << " | "
				   << C.false_fixes << " | " << C.unverifiable << " | "
				   << pct(ratio(C.false_fixes, C.true_fixes + C.false_fixes)) << " | "
				   << pct(falseShareUpper(C.false_fixes, C.true_fixes + C.false_fixes), 3) << " |\n";
			}
			sm << "| " << sysName[s] << " | (used) | " << P.trueFixes + P.falseFixes + P.unverifiable << " | "
			   << P.trueFixes << " | " << P.falseFixes << " | " << P.unverifiable << " | "
			   << pct(ratio(P.falseFixes, P.trueFixes + P.falseFixes)) << " | "
			   << pct(falseShareUpper(P.falseFixes, P.trueFixes + P.falseFixes), 3) << " |\n";
		}
		sm << "\n## Error of the fixes used and accuracy bins\n\n"
		   << "| system | fixes | median [m] | p95 [m] | max [m] | median [deg] | p95 [deg] | max [deg] | "
			  "0.25 m, 2 deg [%] | 0.5 m, 5 deg [%] | 5 m, 10 deg [%] |\n|---|---|---|---|---|---|---|---|---|---|---|\n";
		for (int s = 0; s < 2; s++)
		{
			const auto& P = pooled[s];
			const auto f = [](double v, int prec) {
				if (!std::isfinite(v)) return std::string("n/a");
				std::ostringstream o;
				o << std::fixed << std::setprecision(prec) << v;
				return o.str();
			};
			sm << "| " << sysName[s] << " | " << P.errM.size() << " | " << f(percentile(P.errM, 0.5), 3) << " | "
			   << f(percentile(P.errM, 0.95), 3) << " | " << f(percentile(P.errM, 1.0), 3) << " | "
			   << f(percentile(P.errDeg, 0.5), 2) << " | " << f(percentile(P.errDeg, 0.95), 2) << " | "
			   << f(percentile(P.errDeg, 1.0), 2);
			for (size_t b = 0; b < 3; b++) sm << " | " << pct(ratio(P.bins[b], P.binFrames), 1);
			sm << " |\n";
		}
		sm << "\nAccuracy bins: share of in-map live frames whose fix, composed with the keyframe's ground-truth "
			  "pose, is within the distance and angle of the live frame's ground truth; frames without a fix count "
			  "as outside every bin.\n";
	}
	sm << "\n## Blind distance (episodes between two fixes, pooled over pairs)\n\n"
	   << "| system | pairs | episodes | reaching " << jsonNumber(evo.blind_long_m, 0)
	   << " m | P(episode reaches " << jsonNumber(evo.blind_long_m, 0)
	   << " m) [%] | exact 95 % interval [%] | bootstrap 95 % interval [%] | blind m per km | before first fix | at end |\n"
	   << "|---|---|---|---|---|---|---|---|---|---|\n";
	for (int s = 0; s < 2; s++)
	{
		const auto& P = pooled[s];
		sm << "| " << sysName[s] << " | " << P.pairs << " | " << bp[s].episodes << " | " << bp[s].reaching << " | "
		   << pct(bp[s].p, 2) << " | " << pct(bp[s].exact_lo, 2) << " - " << pct(bp[s].exact_hi, 2) << " | "
		   << pct(bp[s].lo, 1) << " - " << pct(bp[s].hi, 1) << " | "
		   << jsonNumber(P.totalM > 0 ? 1000 * P.blindM / P.totalM : 0, 1) << " | " << P.beforeFirst << " | "
		   << P.atEnd << " |\n";
	}
	sm << "\n";
	for (int s = 0; s < 2; s++)
	{
		const auto& b = bp[s];
		sm << "- " << sysName[s] << ": P(" << jsonNumber(evo.blind_long_m, 0) << " m) = " << b.reaching << " of "
		   << b.episodes << " episodes";
		if (b.episodes == 0)
			sm << " (no episode between two fixes: no bound)\n";
		else if (b.reaching == 0)
			sm << ", 95 % upper bound " << pct(b.exact_hi, 2) << " %\n";
		else
			sm << " (" << pct(b.p, 2) << " %), 95 % interval " << pct(b.exact_lo, 2) << " - " << pct(b.exact_hi, 2)
			   << " %\n";
	}
	sm << "\nThe 95 % intervals are exact binomial (Clopper-Pearson) intervals of the pooled count: they hold "
		  "whatever the true probability, and with no episode reaching the distance the bound is "
		  "1 - 0.025^(1/episodes). The bootstrap interval beside them collapses to 0 - 0 in that case "
		  "(docs/evaluation.md).\n";

	// ---- eval.json
	std::ostringstream js;
	const auto num = [](double v, int prec = 6) { return jsonNumber(v, prec); };
	js << "{\n  \"format\": \"shadyloc eval\",\n  \"version\": " << kEvalVersion
	   << ",\n  \"definitions\": \"docs/evaluation.md\",\n";
	js << "  \"options\": {\"true_max_m\": " << num(evo.true_max_m, 3) << ", \"true_max_deg\": " << num(evo.true_max_deg, 3)
	   << ", \"in_map_m\": " << num(evo.in_map_m, 3) << ", \"in_map_deg\": " << num(evo.in_map_deg, 3)
	   << ", \"blind_long_m\": " << num(evo.blind_long_m, 3) << ", \"bootstrap_samples\": " << evo.bootstrap_samples
	   << ", \"bootstrap_seed\": " << evo.bootstrap_seed << ", \"accuracy_bins\": [";
	for (size_t b = 0; b < kAccuracyBins.size(); b++)
		js << (b ? ", " : "") << "{\"m\": " << num(kAccuracyBins[b][0], 2) << ", \"deg\": " << num(kAccuracyBins[b][1], 1)
		   << "}";
	js << "]},\n";
	js << "  \"provenance\": {\"program\": \"shadyloc eval\", \"build_commit\": " << jsonString(in.buildCommit)
	   << ", \"runs_file\": " << jsonString(fs::path(in.runsPath).filename().string())
	   << ", \"runs_fnv1a64\": " << jsonString(in.runsHash()) << ", \"config\": " << jsonString(in.configWhat)
	   << ", \"config_fnv1a64\": " << jsonString(in.configHash()) << "},\n";
	js << "  \"runs\": [";
	for (size_t i = 0; i < n; i++)
	{
		const auto& r = runs[i];
		const auto& m = maps[i];
		const std::string mapRel = "jobs/map_" + r.name + "/map.kfmap";
		js << (i ? ",\n    " : "\n    ") << "{\"name\": " << jsonString(r.name) << ", \"line\": " << r.line
		   << ", \"rawlog\": " << jsonString(r.rawlog)
		   << ", \"rawlog_fnv1a64\": " << jsonString(io::fnv1a64File(r.rawlogPath)) << ", \"gt\": "
		   << (r.hasGt() ? jsonString(r.gt) : "null") << ", \"gt_fnv1a64\": "
		   << (r.hasGt() ? jsonString(io::fnv1a64File(r.gtPath)) : "null") << ", \"map\": {\"file\": "
		   << jsonString(mapRel) << ", \"fnv1a64\": " << jsonString(io::fnv1a64File((out / mapRel).string()))
		   << ", \"frames\": " << m.frames << ", \"keyframes\": " << m.keyframes << ", \"gt_keyframes\": "
		   << m.gt_keyframes << ", \"breaks\": " << m.breaks << ", \"path_m\": " << num(m.path_m, 3) << "}}";
	}
	js << "\n  ],\n  \"plan\": {\"maps\": " << n << ", \"pairs\": " << jobs.size() - n << ", \"jobs\": " << jobs.size()
	   << "},\n  \"pairs\": [";
	bool firstPair = true;
	for (const auto& j : jobs)
	{
		if (j.isMap) continue;
		const auto& p = pairs[j.index];
		js << (firstPair ? "\n    " : ",\n    ") << "{\"job\": " << j.index << ", \"live\": " << jsonString(p.live)
		   << ", \"map\": " << jsonString(p.map) << ", \"system\": " << jsonString(p.system) << ", \"localisers\": "
		   << jsonString(p.localisers) << ", \"dir\": " << jsonString("pairs/" + pairDirName(j, runs))
		   << ", \"frames\": " << p.frames << ", \"in_map_frames\": " << p.in_map_frames << ", \"fixes\": " << p.fixes
		   << ", \"fixes_in_map\": " << p.fixes_in_map << ", \"coverage_in_map\": "
		   << num(ratio(p.fixes_in_map, p.in_map_frames)) << ", \"ground_truth\": " << (p.ground_truth ? "true" : "false")
		   << ", \"true_coverage_in_map\": "
		   << (p.ground_truth ? num(ratio(p.true_fixes_in_map, p.in_map_frames)) : std::string("null"))
		   << ", \"true_fixes\": " << p.true_fixes << ", \"false_fixes\": " << p.false_fixes << ", \"channels\": [";
		for (size_t c = 0; c < p.channels.size(); c++)
		{
			const auto& C = p.channels[c];
			js << (c ? ", " : "") << "{\"channel\": " << jsonString(C.name) << ", \"accepted\": " << C.accepted
			   << ", \"used\": " << C.used << ", \"accepted_in_map\": " << C.accepted_in_map
			   << ", \"coverage_in_map\": " << num(ratio(C.accepted_in_map, p.in_map_frames));
			if (p.ground_truth)
				js << ", \"true_in_map\": " << C.true_in_map << ", \"true_coverage_in_map\": "
				   << num(ratio(C.true_in_map, p.in_map_frames)) << ", \"true_fixes\": " << C.true_fixes
				   << ", \"false_fixes\": " << C.false_fixes << ", \"unverifiable\": " << C.unverifiable;
			js << "}";
		}
		js << "], \"accuracy\": ";
		if (p.ground_truth)
		{
			js << "[";
			for (size_t b = 0; b < 3; b++) js << (b ? ", " : "") << num(ratio(p.bins[b], p.in_map_frames));
			js << "]";
		}
		else
			js << "null";
		size_t between = 0;
		for (const auto& e : p.episodes) between += e.first == "between";
		js << ", \"blind\": {\"total_m\": " << num(p.total_m, 3) << ", \"blind_m\": " << num(p.blind_m, 3)
		   << ", \"episodes_between\": " << between << ", \"first_fix_frame\": " << p.first_fix_frame
		   << ", \"before_first_fix_m\": " << num(p.before_first_fix_m, 3) << "}, \"global_searches\": "
		   << p.global_searches << "}";
		firstPair = false;
	}
	js << "\n  ],\n  \"table1\": {\"unit\": \"fraction of in-map frames\", \"rows\": [";
	const auto rowJson = [&](const TRow& r) {
		std::ostringstream o;
		o << "{\"live\": " << jsonString(r.live) << ", \"maps\": " << r.maps << ", \"baseline\": " << num(r.base)
		  << ", \"invariant_alone\": " << num(r.inv) << ", \"combined\": " << num(r.comb)
		  << ", \"baseline_self\": " << num(r.baseSelf) << ", \"invariant_alone_self\": " << num(r.invSelf)
		  << ", \"combined_self\": " << num(r.combSelf) << "}";
		return o.str();
	};
	for (size_t i = 0; i < rows.size(); i++) js << (i ? ",\n    " : "\n    ") << rowJson(rows[i]);
	js << "\n  ], \"mean\": " << rowJson(mean) << "},\n";
	js << "  \"ground_truth\": ";
	if (anyGt)
	{
		js << "{";
		for (int s = 0; s < 2; s++)
		{
			const auto& P = pooled[s];
			js << (s ? ",\n    " : "\n    ") << jsonString(sysName[s]) << ": {\"pairs\": " << P.gtPairs
			   << ", \"fixes_used\": {\"true\": " << P.trueFixes << ", \"false\": " << P.falseFixes
			   << ", \"unverifiable\": " << P.unverifiable
			   << ", \"false_share\": " << num(ratio(P.falseFixes, P.trueFixes + P.falseFixes))
			   << ", \"false_share_hi95\": " << num(falseShareUpper(P.falseFixes, P.trueFixes + P.falseFixes))
			   << "}, \"channels\": [";
			for (size_t c = 0; c < P.channelOrder.size(); c++)
			{
				const auto& C = P.channels.at(P.channelOrder[c]);
				js << (c ? ", " : "") << "{\"channel\": " << jsonString(C.name) << ", \"accepted\": " << C.accepted
				   << ", \"true\": " << C.true_fixes << ", \"false\": " << C.false_fixes
				   << ", \"unverifiable\": " << C.unverifiable
				   << ", \"false_share\": " << num(ratio(C.false_fixes, C.true_fixes + C.false_fixes))
				   << ", \"false_share_hi95\": " << num(falseShareUpper(C.false_fixes, C.true_fixes + C.false_fixes))
				   << "}";
			}
			js << "], \"fix_error\": {\"fixes\": " << P.errM.size() << ", \"median_m\": " << num(percentile(P.errM, 0.5))
			   << ", \"p95_m\": " << num(percentile(P.errM, 0.95)) << ", \"max_m\": " << num(percentile(P.errM, 1.0))
			   << ", \"median_deg\": " << num(percentile(P.errDeg, 0.5))
			   << ", \"p95_deg\": " << num(percentile(P.errDeg, 0.95))
			   << ", \"max_deg\": " << num(percentile(P.errDeg, 1.0)) << "}, \"accuracy\": {\"frames\": " << P.binFrames
			   << ", \"within\": [";
			for (size_t b = 0; b < 3; b++) js << (b ? ", " : "") << P.bins[b];
			js << "], \"share\": [";
			for (size_t b = 0; b < 3; b++) js << (b ? ", " : "") << num(ratio(P.bins[b], P.binFrames));
			js << "]}}";
		}
		js << "\n  },\n";
	}
	else
		js << "null,\n";
	js << "  \"blind\": {";
	for (int s = 0; s < 2; s++)
	{
		const auto& P = pooled[s];
		js << (s ? ",\n    " : "\n    ") << jsonString(sysName[s]) << ": {\"pairs\": " << P.pairs
		   << ", \"distance_from\": "
		   << jsonString(P.gtPairs == P.pairs ? "ground truth" : (P.gtPairs == 0 ? "VO" : "ground truth where given, else VO"))
		   << ", \"episodes_between\": " << bp[s].episodes << ", \"episodes_reaching\": " << bp[s].reaching
		   << ", \"p_reach\": " << num(bp[s].p) << ", \"p_reach_ci95_exact\": [" << num(bp[s].exact_lo) << ", "
		   << num(bp[s].exact_hi) << "], \"p_reach_ci95\": [" << num(bp[s].lo) << ", " << num(bp[s].hi)
		   << "], \"before_first_fix\": " << P.beforeFirst << ", \"at_end\": " << P.atEnd
		   << ", \"never_localised\": " << P.neverLocalised << ", \"blind_m\": " << num(P.blindM, 3)
		   << ", \"total_m\": " << num(P.totalM, 3)
		   << ", \"blind_m_per_km\": " << num(P.totalM > 0 ? 1000 * P.blindM / P.totalM : 0, 3) << ", \"lengths_m\": [";
		for (size_t e = 0; e < P.between.size(); e++) js << (e ? ", " : "") << num(P.between[e], 3);
		js << "]}";
	}
	js << "\n  }\n}\n";

	// ---- timing.json (apart: the results compare byte for byte)
	std::ostringstream tj;
	tj << "{\n  \"format\": \"shadyloc eval timing\",\n  \"version\": 1,\n  \"wall_s\": "
	   << (wall_s >= 0 ? num(wall_s, 3) : std::string("null")) << ",\n  \"jobs\": [";
	for (const auto& j : jobs)
		tj << (j.index ? ",\n    " : "\n    ") << "{\"job\": " << j.index << ", \"name\": " << jsonString(j.name)
		   << ", \"wall_s\": " << readJobWall((out / "jobs" / j.name / "job_timing.json").string()) << "}";
	tj << "\n  ]\n}\n";

	// ---- figures_inputs.tsv: the per-pair frames.csv paths (relative to
	// OUTDIR) Figures 7-9 are drawn from (below), for redrawing with
	// `shadyloc figures`.
	std::ostringstream fig;
	fig << "live\tmap\tbaseline_frames\tcombined_frames\n";
	for (size_t i = 0; i < n; i++)
		for (size_t m = 0; m < n; m++)
		{
			if (m == i) continue;
			const auto& jb = jobs[pairJobIndex(n, i, m, EvalSystem::Baseline)];
			const auto& jc = jobs[pairJobIndex(n, i, m, EvalSystem::Combined)];
			fig << runs[i].name << '\t' << runs[m].name << "\tpairs/" << pairDirName(jb, runs) << "/frames.csv\tpairs/"
				<< pairDirName(jc, runs) << "/frames.csv\n";
		}

	// ---- all outputs together, or none
	io::OutputTransaction tx;
	tx.setMinLoggingLevel(mrpt::system::LVL_ERROR);
	tx.addInput((out / "jobs").string(), "job outputs");
	tx.addInput(in.runsPath, "run list");
	const auto put = [&](const char* name, const std::string& text) {
		const std::string tmp = tx.addFile((out / name).string(), name);
		std::ofstream f(tmp, std::ios::binary);
		f << text;
		f.close();
		if (!f) throw std::runtime_error("cannot write '" + tmp + "'");
	};
	put("table1.md", md.str());
	put("table1.csv", csv.str());
	put("summary.md", sm.str());
	put("eval.json", js.str());
	put("timing.json", tj.str());
	put("figures_inputs.tsv", fig.str());
	const fs::path pairsTmp = tx.addDirectory((out / "pairs").string(), "pairs", "shadyloc eval pairs folder");
	for (const auto& j : jobs)
	{
		if (j.isMap) continue;
		const fs::path d = pairsTmp / pairDirName(j, runs);
		fs::create_directory(d);
		for (const char* f : kPairFiles) fs::copy_file(out / "jobs" / j.name / f, d / f);
	}
	// ---- Figures 7-9 from the pairs' frames.csv (docs/figures.md): Figure 7
	// per (live, map), Figure 8 per live run, Figure 9 from the pooled
	// episodes of eval.json, so the figure and the JSON agree.
	const fs::path figTmp = tx.addDirectory((out / "figures").string(), "figures", "shadyloc eval figures folder");
	for (size_t i = 0; i < n; i++)
	{
		std::vector<TFigurePair> rows;
		for (size_t m = 0; m < n; m++)
		{
			if (m == i) continue;
			const auto csvOf = [&](EvalSystem s) {
				return (pairsTmp / pairDirName(jobs[pairJobIndex(n, i, m, s)], runs) / "frames.csv").string();
			};
			rows.push_back({runs[m].name, csvOf(EvalSystem::Baseline), csvOf(EvalSystem::Combined)});
			figure7(runs[i].name, runs[m].name, rows.back().baselineCsv, rows.back().combinedCsv,
					(figTmp / ("figure7_" + runs[i].name + "__" + runs[m].name + ".png")).string());
		}
		figure8(runs[i].name, rows, (figTmp / ("figure8_" + runs[i].name + ".png")).string());
	}
	figure9(pooled[0].between, pooled[1].between, (figTmp / "figure9.png").string(),
			pooled[0].gtPairs + pooled[1].gtPairs > 0 ? "ground truth" : "VO", evo.blind_long_m);
	tx.commit();
	return {md.str(), sm.str()};
}

}  // namespace shadyloc::eval
