/* ShadyLoc — the leave-one-out merge's outputs, one writer each (MergeTables.h,
 * docs/evaluation.md): table1.md, table1.csv, summary.md, eval.json,
 * timing.json, figures_inputs.tsv. */
#include <shadyloc/io/FileHash.h>

#include "Json.h"
#include "MergeTables.h"

#include <cmath>
#include <filesystem>
#include <iomanip>
#include <sstream>

namespace shadyloc::eval
{
namespace fs = std::filesystem;

namespace
{
/** v with `decimals` decimals, "n/a" if not finite (the Markdown tables). */
std::string fixedText(double v, int decimals)
{
	if (!std::isfinite(v)) return "n/a";
	std::ostringstream s;
	s << std::fixed << std::setprecision(decimals) << v;
	return s.str();
}
/** A share [0..1] as a percentage. */
std::string pct(double v, int decimals = 2) { return fixedText(100 * v, decimals); }
/** ... in the CSV: empty if unknown. */
std::string csvPct(double v) { return std::isfinite(v) ? pct(v, 4) : std::string(); }

double perKm(double blindM, double totalM) { return totalM > 0 ? 1000 * blindM / totalM : 0; }

/** Table I's rows, then the mean. */
std::vector<const TRow*> rowsAndMean(const TMerged& m)
{
	std::vector<const TRow*> all;
	for (const auto& r : m.rows) all.push_back(&r);
	all.push_back(&m.mean);
	return all;
}

// ---- summary.md ---------------------------------------------------------------------------------
/** One line of the fixes table: a localiser's counts, or the fixes used. */
void fixesLine(std::ostream& sm, const char* system, const std::string& what, size_t accepted, size_t t, size_t f, size_t u)
{
	sm << "| " << system << " | " << what << " | " << accepted << " | " << t << " | " << f << " | " << u << " | "
	   << pct(ratio(f, t + f)) << " | " << pct(falseShareUpper(f, t + f), 3) << " |\n";
}

void fixesSection(std::ostream& sm, const TMerged& m)
{
	sm << "## Fixes against ground truth (pairs with ground truth on both sides)\n\n"
	   << "| system | localiser | accepted | true | false | unverifiable | false share [%] | exact 95 % upper "
		  "bound [%] |\n"
	   << "|---|---|---|---|---|---|---|---|\n";
	for (int s = 0; s < m.systems(); s++)
	{
		const auto& P = m.pooled[s];
		for (const auto& name : P.channelOrder)
		{
			const auto& C = P.channels.at(name);
			fixesLine(sm, kSystemNames[s], name, C.accepted, C.true_fixes, C.false_fixes, C.unverifiable);
		}
		fixesLine(sm, kSystemNames[s], "(used)", P.trueFixes + P.falseFixes + P.unverifiable, P.trueFixes, P.falseFixes,
				  P.unverifiable);
	}
}

void errorSection(std::ostream& sm, const TMerged& m)
{
	sm << "\n## Error of the fixes used and accuracy bins\n\n"
	   << "| system | fixes | median [m] | p95 [m] | max [m] | median [deg] | p95 [deg] | max [deg] | "
		  "0.25 m, 2 deg [%] | 0.5 m, 5 deg [%] | 5 m, 10 deg [%] |\n|---|---|---|---|---|---|---|---|---|---|---|\n";
	for (int s = 0; s < m.systems(); s++)
	{
		const auto& P = m.pooled[s];
		sm << "| " << kSystemNames[s] << " | " << P.errM.size();
		for (const double q : {0.5, 0.95, 1.0}) sm << " | " << fixedText(percentile(P.errM, q), 3);
		for (const double q : {0.5, 0.95, 1.0}) sm << " | " << fixedText(percentile(P.errDeg, q), 2);
		for (size_t b = 0; b < 3; b++) sm << " | " << pct(ratio(P.bins[b], P.binFrames), 1);
		sm << " |\n";
	}
	sm << "\nAccuracy bins: share of in-map live frames whose fix, composed with the keyframe's ground-truth "
		  "pose, is within the distance and angle of the live frame's ground truth; frames without a fix count "
		  "as outside every bin.\n";
}

void blindTable(std::ostream& sm, const TMerged& m)
{
	const std::string d = fixedText(m.evo.blind_long_m, 0);
	sm << "\n## Blind distance (episodes between two fixes, pooled over pairs)\n\n"
	   << "| system | pairs | episodes | reaching " << d << " m | P(episode reaches " << d
	   << " m) [%] | exact 95 % interval [%] | bootstrap 95 % interval [%] | blind m per km | before first fix | at end |\n"
	   << "|---|---|---|---|---|---|---|---|---|---|\n";
	for (int s = 0; s < m.systems(); s++)
	{
		const auto& P = m.pooled[s];
		const auto& b = P.blind;
		sm << "| " << kSystemNames[s] << " | " << P.pairs << " | " << b.episodes << " | " << b.reaching << " | "
		   << pct(b.p, 2) << " | " << pct(b.exact_lo, 2) << " - " << pct(b.exact_hi, 2) << " | " << pct(b.lo, 1)
		   << " - " << pct(b.hi, 1) << " | " << fixedText(perKm(P.blindM, P.totalM), 1) << " | " << P.beforeFirst
		   << " | " << P.atEnd << " |\n";
	}
}

/** One line per system: P(reaching the distance) with its exact interval. */
void blindLines(std::ostream& sm, const TMerged& m)
{
	sm << "\n";
	for (int s = 0; s < m.systems(); s++)
	{
		const auto& b = m.pooled[s].blind;
		sm << "- " << kSystemNames[s] << ": P(" << fixedText(m.evo.blind_long_m, 0) << " m) = " << b.reaching << " of "
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
}

// ---- eval.json ----------------------------------------------------------------------------------
Json optionsJson(const TEvalOptions& o)
{
	Json bins = Json::array();
	for (const auto& b : kAccuracyBins) bins.push_back({{"m", fixedNumber(b[0], 2)}, {"deg", fixedNumber(b[1], 1)}});
	return {{"true_max_m", fixedNumber(o.true_max_m, 3)},	   {"true_max_deg", fixedNumber(o.true_max_deg, 3)},
			{"in_map_m", fixedNumber(o.in_map_m, 3)},		   {"in_map_deg", fixedNumber(o.in_map_deg, 3)},
			{"blind_long_m", fixedNumber(o.blind_long_m, 3)}, {"bootstrap_samples", o.bootstrap_samples},
			{"bootstrap_seed", o.bootstrap_seed},			   {"accuracy_bins", bins}};
}

Json provenanceJson(const TEvalInputs& in)
{
	Json p = {{"program", "shadyloc eval"},
			  {"build_commit", in.buildCommit},
			  {"runs_file", fs::path(in.runsPath).filename().string()},
			  {"runs_fnv1a64", in.runsHash()},
			  {"config", in.configWhat},
			  {"config_fnv1a64", in.configHash()}};
	if (in.hasControl())
	{
		// The layer alone (its name and hash); the control ran with the -c files under it.
		p["control_config"] = fs::path(in.controlPath).filename().string();
		p["control_fnv1a64"] = in.controlHash();
	}
	return p;
}

/** A map job's map: file, fingerprint, what its job counted. */
Json mapJson(const TMerged& m, const std::string& jobName, const TMapRecord& rec)
{
	const std::string mapRel = "jobs/" + jobName + "/map.kfmap";
	return {{"file", mapRel},
			{"fnv1a64", io::fnv1a64File((fs::path(m.outDir) / mapRel).string())},
			{"frames", rec.frames},
			{"keyframes", rec.keyframes},
			{"gt_keyframes", rec.gt_keyframes},
			{"breaks", rec.breaks},
			{"path_m", fixedNumber(rec.path_m, 3)}};
}

/** Each run's inputs and its map (file, fingerprint, what its job counted). */
Json runsJson(const TMerged& m)
{
	Json runs = Json::array();
	for (size_t i = 0; i < m.runs().size(); i++)
	{
		const auto& r = m.runs()[i];
		Json run = {{"name", r.name},
					{"line", r.line},
					{"rawlog", r.rawlog},
					{"rawlog_fnv1a64", io::fnv1a64File(r.rawlogPath)},
					{"gt", r.hasGt() ? Json(r.gt) : Json()},
					{"gt_fnv1a64", r.hasGt() ? Json(io::fnv1a64File(r.gtPath)) : Json()},
					{"map", mapJson(m, mapJobName(r.name, EvalSystem::Baseline), m.maps[i])}};
		if (m.control())
			run["control_map"] = mapJson(m, mapJobName(r.name, EvalSystem::Control), m.controlMaps[i]);
		runs.push_back(run);
	}
	return runs;
}

/** A pair's localisers: fixes accepted, used, in the map (true ones with ground truth). */
Json pairChannelsJson(const TPairRecord& p)
{
	Json list = Json::array();
	for (const auto& C : p.channels)
	{
		Json c = {{"channel", C.name},
				  {"accepted", C.accepted},
				  {"used", C.used},
				  {"accepted_in_map", C.accepted_in_map},
				  {"coverage_in_map", fixedNumber(ratio(C.accepted_in_map, p.in_map_frames))}};
		if (p.ground_truth)
		{
			c["true_in_map"] = C.true_in_map;
			c["true_coverage_in_map"] = fixedNumber(ratio(C.true_in_map, p.in_map_frames));
			c["true_fixes"] = C.true_fixes;
			c["false_fixes"] = C.false_fixes;
			c["unverifiable"] = C.unverifiable;
		}
		list.push_back(c);
	}
	return list;
}

/** The share of in-map frames within each accuracy bin; null without ground truth. */
Json accuracyJson(const TPairRecord& p)
{
	if (!p.ground_truth) return nullptr;
	Json a = Json::array();
	for (const size_t within : p.bins) a.push_back(fixedNumber(ratio(within, p.in_map_frames)));
	return a;
}

Json pairJson(const TMerged& m, const TEvalJob& j)
{
	const auto& p = m.pairs[j.index];
	size_t between = 0;
	for (const auto& e : p.episodes) between += e.first == "between";
	const Json blind = {{"total_m", fixedNumber(p.total_m, 3)},
						{"blind_m", fixedNumber(p.blind_m, 3)},
						{"episodes_between", between},
						{"first_fix_frame", p.first_fix_frame},
						{"before_first_fix_m", fixedNumber(p.before_first_fix_m, 3)}};
	return {{"job", j.index},
			{"live", p.live},
			{"map", p.map},
			{"system", p.system},
			{"localisers", p.localisers},
			{"dir", "pairs/" + pairDirName(j, m.runs())},
			{"frames", p.frames},
			{"in_map_frames", p.in_map_frames},
			{"fixes", p.fixes},
			{"fixes_in_map", p.fixes_in_map},
			{"coverage_in_map", fixedNumber(ratio(p.fixes_in_map, p.in_map_frames))},
			{"ground_truth", p.ground_truth},
			{"true_coverage_in_map", p.ground_truth ? fixedNumber(ratio(p.true_fixes_in_map, p.in_map_frames)) : Json()},
			{"true_fixes", p.true_fixes},
			{"false_fixes", p.false_fixes},
			{"channels", pairChannelsJson(p)},
			{"accuracy", accuracyJson(p)},
			{"blind", blind},
			{"global_searches", p.global_searches}};
}

Json pairsJson(const TMerged& m)
{
	Json pairs = Json::array();
	for (const auto& j : m.jobs)
		if (!j.isMap) pairs.push_back(pairJson(m, j));
	return pairs;
}

Json rowJson(const TRow& r, bool control)
{
	Json row = {{"live", r.live},
				{"maps", r.maps},
				{"baseline", fixedNumber(r.base)},
				{"invariant_alone", fixedNumber(r.inv)},
				{"combined", fixedNumber(r.comb)},
				{"baseline_self", fixedNumber(r.baseSelf)},
				{"invariant_alone_self", fixedNumber(r.invSelf)},
				{"combined_self", fixedNumber(r.combSelf)}};
	if (control)
	{
		row["control"] = fixedNumber(r.ctl);
		row["control_self"] = fixedNumber(r.ctlSelf);
	}
	return row;
}

Json table1Json(const TMerged& m)
{
	Json rows = Json::array();
	for (const auto& r : m.rows) rows.push_back(rowJson(r, m.control()));
	return {{"unit", "fraction of in-map frames"}, {"rows", rows}, {"mean", rowJson(m.mean, m.control())}};
}

/** True, false and unverifiable fixes, the false share and its exact upper bound. */
Json fixCountsJson(Json counts, size_t t, size_t f, size_t u)
{
	counts["true"] = t;
	counts["false"] = f;
	counts["unverifiable"] = u;
	counts["false_share"] = fixedNumber(ratio(f, t + f));
	counts["false_share_hi95"] = fixedNumber(falseShareUpper(f, t + f));
	return counts;
}

/** A system's fixes against ground truth, pooled over its pairs with it. */
Json systemTruthJson(const TPooled& P)
{
	Json channels = Json::array();
	for (const auto& name : P.channelOrder)
	{
		const auto& C = P.channels.at(name);
		channels.push_back(fixCountsJson({{"channel", C.name}, {"accepted", C.accepted}}, C.true_fixes, C.false_fixes,
										 C.unverifiable));
	}
	Json error = {{"fixes", P.errM.size()}};
	for (const auto& [what, errors] : {std::pair<const char*, const std::vector<double>*>{"m", &P.errM}, {"deg", &P.errDeg}})
		for (const auto& [name, q] : {std::pair<const char*, double>{"median_", 0.5}, {"p95_", 0.95}, {"max_", 1.0}})
			error[std::string(name) + what] = fixedNumber(percentile(*errors, q));
	Json within = Json::array(), share = Json::array();
	for (const size_t b : P.bins)
	{
		within.push_back(b);
		share.push_back(fixedNumber(ratio(b, P.binFrames)));
	}
	return {{"pairs", P.gtPairs},
			{"fixes_used", fixCountsJson(Json::object(), P.trueFixes, P.falseFixes, P.unverifiable)},
			{"channels", channels},
			{"fix_error", error},
			{"accuracy", {{"frames", P.binFrames}, {"within", within}, {"share", share}}}};
}

Json groundTruthJson(const TMerged& m)
{
	if (!m.anyGt()) return nullptr;
	Json g = Json::object();
	for (int s = 0; s < m.systems(); s++) g[kSystemNames[s]] = systemTruthJson(m.pooled[s]);
	return g;
}

/** A system's blind episodes pooled over its pairs. */
Json systemBlindJson(const TPooled& P)
{
	const auto& b = P.blind;
	Json lengths = Json::array();
	for (const double l : P.between) lengths.push_back(fixedNumber(l, 3));
	const char* from = P.gtPairs == P.pairs ? "ground truth" : (P.gtPairs == 0 ? "VO" : "ground truth where given, else VO");
	return {{"pairs", P.pairs},
			{"distance_from", from},
			{"episodes_between", b.episodes},
			{"episodes_reaching", b.reaching},
			{"p_reach", fixedNumber(b.p)},
			{"p_reach_ci95_exact", {fixedNumber(b.exact_lo), fixedNumber(b.exact_hi)}},
			{"p_reach_ci95", {fixedNumber(b.lo), fixedNumber(b.hi)}},
			{"before_first_fix", P.beforeFirst},
			{"at_end", P.atEnd},
			{"never_localised", P.neverLocalised},
			{"blind_m", fixedNumber(P.blindM, 3)},
			{"total_m", fixedNumber(P.totalM, 3)},
			{"blind_m_per_km", fixedNumber(perKm(P.blindM, P.totalM), 3)},
			{"lengths_m", lengths}};
}

/** Every system's blind episodes, by name. */
Json blindJson(const TMerged& m)
{
	Json b = Json::object();
	for (int s = 0; s < m.systems(); s++) b[kSystemNames[s]] = systemBlindJson(m.pooled[s]);
	return b;
}

/** The Markdown table's header: the columns, control's after combined's when there is one. */
std::string table1Header(bool control)
{
	if (!control)
		return "| live run | maps | baseline | invariant alone | combined | self-reported: baseline | invariant alone | "
			   "combined |\n|---|---|---|---|---|---|---|---|\n";
	return "| live run | maps | baseline | invariant alone | combined | control | self-reported: baseline | "
		   "invariant alone | combined | control |\n|---|---|---|---|---|---|---|---|---|---|\n";
}

/** A job's wall time from its job_timing.json; null if it has none. */
Json jobWall(const std::string& path)
{
	const Json t = readJsonFile(path);
	return t.is_object() && t.contains("wall_s") && t["wall_s"].is_number() ? fixedNumber(t["wall_s"].get<double>(), 3)
																			: Json();
}
}  // namespace

std::string table1Markdown(const TMerged& m)
{
	std::ostringstream md;
	md << "# Table I: coverage, leave-one-out\n\n"
	   << "Each live run localised against the map of every other run (" << m.runs().size() - 1
	   << " maps), averaged over the maps: the share of in-map frames with a fix [%]. True coverage counts fixes "
		  "within 0.5 m and 2 deg of the ground truth; self-reported counts every fix. Invariant alone is the "
		  "combined run's invariant localiser (docs/evaluation.md).";
	if (m.control())
		md << " Control is the baseline (monochrome alone) on maps of its own, maps and live runs both with "
		   << fs::path(m.in.controlPath).filename().string()
		   << " layered over the configs: the budget-matched control.";
	md << "\n\n" << table1Header(m.control());
	for (const auto* r : rowsAndMean(m))
	{
		md << "| " << (r == &m.mean ? "**mean**" : r->live) << " | " << r->maps << " | " << pct(r->base) << " | "
		   << pct(r->inv) << " | " << pct(r->comb);
		if (m.control()) md << " | " << pct(r->ctl);
		md << " | " << pct(r->baseSelf) << " | " << pct(r->invSelf) << " | " << pct(r->combSelf);
		if (m.control()) md << " | " << pct(r->ctlSelf);
		md << " |\n";
	}
	if (!m.anyGt()) md << "\nNo run pair has ground truth on both sides: true coverage is n/a.\n";
	return md.str();
}

std::string table1Csv(const TMerged& m)
{
	std::ostringstream csv;
	// The control's columns go last: the others keep their places for readers of the two-system table.
	csv << "live,maps,baseline_pct,invariant_pct,combined_pct,baseline_self_pct,invariant_self_pct,combined_self_pct"
		<< (m.control() ? ",control_pct,control_self_pct\n" : "\n");
	for (const auto* r : rowsAndMean(m))
	{
		csv << r->live << ',' << r->maps << ',' << csvPct(r->base) << ',' << csvPct(r->inv) << ',' << csvPct(r->comb)
			<< ',' << csvPct(r->baseSelf) << ',' << csvPct(r->invSelf) << ',' << csvPct(r->combSelf);
		if (m.control()) csv << ',' << csvPct(r->ctl) << ',' << csvPct(r->ctlSelf);
		csv << '\n';
	}
	return csv.str();
}

std::string summaryMarkdown(const TMerged& m)
{
	std::ostringstream sm;
	sm << "# Leave-one-out summary\n\n";
	if (m.anyGt())
	{
		fixesSection(sm, m);
		errorSection(sm, m);
	}
	blindTable(sm, m);
	blindLines(sm, m);
	return sm.str();
}

std::string evalJson(const TMerged& m)
{
	const size_t n = mapJobCount(m.runs().size(), m.control());
	const Json doc = {{"format", "shadyloc eval"},
					  {"version", kEvalVersion},
					  {"definitions", "docs/evaluation.md"},
					  {"options", optionsJson(m.evo)},
					  {"provenance", provenanceJson(m.in)},
					  {"runs", runsJson(m)},
					  {"plan", {{"maps", n}, {"pairs", m.jobs.size() - n}, {"jobs", m.jobs.size()}}},
					  {"pairs", pairsJson(m)},
					  {"table1", table1Json(m)},
					  {"ground_truth", groundTruthJson(m)},
					  {"blind", blindJson(m)}};
	return writeJson(doc, {"", "/runs", "/pairs", "/table1/rows", "/ground_truth", "/blind"});
}

std::string evalTimingJson(const TMerged& m, double wall_s)
{
	Json jobs = Json::array();
	for (const auto& j : m.jobs)
		jobs.push_back({{"job", j.index},
						{"name", j.name},
						{"wall_s", jobWall((fs::path(m.outDir) / "jobs" / j.name / "job_timing.json").string())}});
	const Json doc = {{"format", "shadyloc eval timing"},
					  {"version", 1},
					  {"wall_s", wall_s >= 0 ? fixedNumber(wall_s, 3) : Json()},
					  {"jobs", jobs}};
	return writeJson(doc, {"", "/jobs"});
}

std::string figuresInputs(const TMerged& m)
{
	const auto& runs = m.runs();
	const size_t n = runs.size();
	std::ostringstream fig;
	fig << "live\tmap\tbaseline_frames\tcombined_frames\n";
	for (size_t i = 0; i < n; i++)
		for (size_t k = 0; k < n; k++)
		{
			if (k == i) continue;
			const auto& jb = m.pairJob(i, k, EvalSystem::Baseline);
			const auto& jc = m.pairJob(i, k, EvalSystem::Combined);
			fig << runs[i].name << '\t' << runs[k].name << "\tpairs/" << pairDirName(jb, runs) << "/frames.csv\tpairs/"
				<< pairDirName(jc, runs) << "/frames.csv\n";
		}
	return fig.str();
}

}  // namespace shadyloc::eval
