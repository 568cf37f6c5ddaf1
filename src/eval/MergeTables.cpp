/* ShadyLoc — the leave-one-out merge: collect the jobs' records, make the tables. */
#include <shadyloc/map/CKeyframeMap.h>

#include "MergeTables.h"

#include <algorithm>
#include <cmath>
#include <filesystem>

namespace shadyloc::eval
{
namespace fs = std::filesystem;

namespace
{
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

/** A map job's record into m.maps; "" or why it is unusable. */
std::string readMapJob(TMerged& m, const TEvalJob& j, const fs::path& dir)
{
	if (!fs::exists(dir / "map.kfmap")) return "no map.kfmap in '" + dir.string() + "'";
	auto& rec = (j.system == EvalSystem::Control ? m.controlMaps : m.maps)[j.run];
	rec = readMapRecord((dir / "map.tsv").string());
	return checkMapFile((dir / "map.kfmap").string(), rec);
}

/** A pair job's record into m.pairs; "" or why it is unusable. */
std::string readPairJob(TMerged& m, const TEvalJob& j, const fs::path& dir)
{
	for (const char* f : kPairFiles)
		if (!fs::is_regular_file(dir / f)) return "no " + std::string(f) + " in '" + dir.string() + "'";
	const auto& p = m.pairs[j.index] = readPairRecord((dir / "pair.tsv").string());
	if (p.live != m.runs()[j.run].name || p.map != m.runs()[j.map].name || p.system != toString(j.system))
		return "'" + (dir / "pair.tsv").string() + "' is of pair " + p.live + "/" + p.map + "/" + p.system;
	return "";
}

/** A job's record into m; "" or why it is unusable (a read error included). */
std::string readJob(TMerged& m, const TEvalJob& j)
{
	const fs::path dir = fs::path(m.outDir) / "jobs" / j.name;
	try
	{
		if (!fs::is_directory(dir)) return "no output ('" + dir.string() + "')";
		return j.isMap ? readMapJob(m, j, dir) : readPairJob(m, j, dir);
	}
	catch (const std::exception& e)
	{
		return e.what();
	}
}

/** "map of run 'a'" or "live run 'a' against the map of 'b', baseline". */
std::string jobWhat(const TMerged& m, const TEvalJob& j)
{
	const auto& runs = m.runs();
	if (j.isMap) return (j.system == EvalSystem::Control ? "control's map of run '" : "map of run '") + runs[j.run].name + "'";
	return "live run '" + runs[j.run].name + "' against the map of '" + runs[j.map].name + "', " + toString(j.system);
}

/** The control's columns of live run i's row, averaged over the maps as the others. */
void controlColumns(const TMerged& m, size_t i, TRow& row)
{
	std::vector<double> t, s;
	bool truth = true;
	for (size_t k = 0; k < m.runs().size(); k++)
	{
		if (k == i) continue;
		const auto& p = m.pairs[m.pairJob(i, k, EvalSystem::Control).index];
		truth &= p.ground_truth;
		t.push_back(ratio(p.true_fixes_in_map, p.in_map_frames));
		s.push_back(ratio(p.fixes_in_map, p.in_map_frames));
	}
	if (truth && row.truth) row.ctl = meanOf(t);
	row.ctlSelf = meanOf(s);
}

/** One row of Table I: live run i against every other run's map. */
TRow tableRow(const TMerged& m, size_t i)
{
	const size_t n = m.runs().size();
	TRow row;
	row.live = m.runs()[i].name;
	row.truth = true;
	std::vector<double> b, v, c, bs, vs, cs;
	for (size_t k = 0; k < n; k++)
	{
		if (k == i) continue;
		row.maps++;
		const auto& pb = m.pairs[m.pairJob(i, k, EvalSystem::Baseline).index];
		const auto& pc = m.pairs[m.pairJob(i, k, EvalSystem::Combined).index];
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
	if (m.control()) controlColumns(m, i, row);
	return row;
}

/** The mean row: each column averaged over the rows that have it. */
TRow meanRow(const std::vector<TRow>& rows, size_t maps)
{
	TRow mean;
	mean.live = "mean";
	mean.maps = maps;
	const auto column = [&](double TRow::*f) {
		std::vector<double> v;
		for (const auto& r : rows) v.push_back(r.*f);
		return meanOf(v);
	};
	mean.base = column(&TRow::base);
	mean.inv = column(&TRow::inv);
	mean.comb = column(&TRow::comb);
	mean.baseSelf = column(&TRow::baseSelf);
	mean.invSelf = column(&TRow::invSelf);
	mean.combSelf = column(&TRow::combSelf);
	mean.ctl = column(&TRow::ctl);
	mean.ctlSelf = column(&TRow::ctlSelf);
	return mean;
}

/** What only pairs with ground truth add to their system's pool. */
void poolGroundTruth(TPooled& P, const TPairRecord& p)
{
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

/** A pair's record into its system's pool. */
void poolPair(TPooled& P, const TPairRecord& p)
{
	P.pairs++;
	for (const auto& e : p.episodes)
	{
		if (e.first == "between")
			P.between.push_back(e.second);
		else if (e.first == "at_end")
			P.atEnd++;
		else
			P.beforeFirst++;
	}
	P.neverLocalised += p.first_fix_frame < 0;
	P.blindM += p.blind_m;
	P.totalM += p.total_m;
	if (p.ground_truth) poolGroundTruth(P, p);
}
}  // namespace

double ratio(size_t a, size_t b) { return b ? static_cast<double>(a) / static_cast<double>(b) : kNaN; }

double falseShareUpper(size_t falseFixes, size_t fixes)
{
	return fixes ? clopperPearson(falseFixes, fixes, 0.95).hi : kNaN;
}

double percentile(std::vector<double> v, double p)
{
	if (v.empty()) return kNaN;
	std::sort(v.begin(), v.end());
	return v[static_cast<size_t>(std::round(p * static_cast<double>(v.size() - 1)))];
}

std::string pairDirName(const TEvalJob& j, const std::vector<TRun>& runs)
{
	return runs[j.run].name + "__" + runs[j.map].name + "__" + toString(j.system);
}

void collectRecords(TMerged& m)
{
	m.maps.assign(m.runs().size(), {});
	m.controlMaps.assign(m.control() ? m.runs().size() : 0, {});
	m.pairs.assign(m.jobs.size(), {});
	std::string missing;
	size_t nMissing = 0;
	for (const auto& j : m.jobs)
	{
		const std::string why = readJob(m, j);
		if (why.empty()) continue;
		nMissing++;
		missing += "\n  job " + std::to_string(j.index) + " (" + jobWhat(m, j) + "): " + why;
	}
	if (nMissing)
		throw std::runtime_error(
			"cannot merge: " + std::to_string(nMissing) + " of " + std::to_string(m.jobs.size()) +
			" jobs have no usable output in '" + (fs::path(m.outDir) / "jobs").string() + "':" + missing +
			"\nrun them (shadyloc eval --runs " + m.in.runsPath + " -o " + m.outDir + " ... --job K), then merge again");
}

void makeTables(TMerged& m)
{
	const size_t n = m.runs().size();
	m.rows.clear();
	for (size_t i = 0; i < n; i++) m.rows.push_back(tableRow(m, i));
	m.mean = meanRow(m.rows, n - 1);
	for (const auto& j : m.jobs)
		if (!j.isMap) poolPair(m.pooled[static_cast<int>(j.system)], m.pairs[j.index]);
	for (auto& P : m.pooled) P.blind = blindProbability(P.between, m.evo);
}

}  // namespace shadyloc::eval
