/* shadyloc figures: the paper's Figures 7, 8 and 9 from `shadyloc localise`
 * output folders (docs/figures.md). */
#include "Command.h"
#include "CommandLine.h"

#include <shadyloc/eval/Figures.h>
#include <shadyloc/eval/LocaliseOutputs.h>
#include <shadyloc/io/OutputTransaction.h>

#include <mrpt/3rdparty/tclap/CmdLine.h>

#include <algorithm>
#include <filesystem>
#include <iostream>

namespace cmd_figures
{
using namespace shadyloc;
namespace fs = std::filesystem;

struct TPairSpec
{
	std::string live, map, baselineDir, combinedDir;
	std::string liveHash, mapHash;	//!< from summary.json ("" without one)
	std::string baselineCsv() const { return (fs::path(baselineDir) / "frames.csv").string(); }
	std::string combinedCsv() const { return (fs::path(combinedDir) / "frames.csv").string(); }
};

std::vector<std::string> splitCommas(const std::string& s)
{
	std::vector<std::string> f;
	size_t a = 0;
	for (;;)
	{
		const size_t c = s.find(',', a);
		f.push_back(s.substr(a, c == std::string::npos ? std::string::npos : c - a));
		if (c == std::string::npos) return f;
		a = c + 1;
	}
}

/** The names are labels the user chooses, but one that names neither the
 * run's rawlog nor its map (by file or folder name) is likely a slip:
 * said, not refused (eval's run names need not be file names). */
void warnUnmatchedNames(const TPairSpec& p, const std::string& spec)
{
	const std::string live = eval::localiseProvenance(p.baselineDir, "live"),
					  map = eval::localiseProvenance(p.baselineDir, "map");
	const auto names = [](const std::string& path, const std::string& name) {
		const fs::path q(path);
		return q.stem() == name || q.parent_path().filename() == name || q.parent_path().filename() == "map_" + name;
	};
	if (!live.empty() && !names(live, p.live))
		std::cerr << "shadyloc figures: warning: --pair '" << spec << "': live run name '" << p.live
				  << "' matches nothing in its summary.json (live rawlog '" << live << "'); labelled as given\n";
	if (!map.empty() && !names(map, p.map))
		std::cerr << "shadyloc figures: warning: --pair '" << spec << "': map name '" << p.map
				  << "' matches nothing in its summary.json (map '" << map << "'); labelled as given\n";
}

TPairSpec parsePair(const std::string& s)
{
	const auto f = splitCommas(s);
	if (f.size() != 4 || std::any_of(f.begin(), f.end(), [](const std::string& x) { return x.empty(); }))
		throw std::invalid_argument("--pair '" + s + "': expected LIVE,MAP,BASELINE_DIR,COMBINED_DIR");
	TPairSpec p{f[0], f[1], f[2], f[3], "", ""};
	for (const auto& csv : {p.baselineCsv(), p.combinedCsv()})
		if (!fs::is_regular_file(csv))
			throw std::runtime_error("--pair '" + s + "': '" + csv + "' does not exist (a shadyloc localise OUTDIR?)");
	// The two runs of one pair: the same live run against the same map.
	for (const char* key : {"live", "map"})
	{
		const std::string b = eval::localiseProvenance(p.baselineDir, std::string(key) + "_fnv1a64"),
						  c = eval::localiseProvenance(p.combinedDir, std::string(key) + "_fnv1a64");
		if (!b.empty() && !c.empty() && b != c)
			throw std::invalid_argument(
				"--pair '" + s + "': the baseline run used " + key + " '" + eval::localiseProvenance(p.baselineDir, key) +
				"', the combined run " + key + " '" + eval::localiseProvenance(p.combinedDir, key) +
				"' (their summary.json): not one pair");
	}
	warnUnmatchedNames(p, s);
	p.liveHash = eval::localiseProvenance(p.baselineDir, "live_fnv1a64");
	p.mapHash = eval::localiseProvenance(p.baselineDir, "map_fnv1a64");
	return p;
}

/** A name must mean one thing: the same LIVE (or MAP) name for two
 * different live runs (maps), or two names for one, would pool or label
 * the figures wrongly. */
void checkNames(const TPairSpec& a, const TPairSpec& b)
{
	const auto check = [](const std::string& what, const std::string& nameA, const std::string& hashA,
						   const std::string& nameB, const std::string& hashB) {
		if (hashA.empty() || hashB.empty()) return;
		if (nameA == nameB && hashA != hashB)
			throw std::invalid_argument(
				"--pair: " + what + " name '" + nameA + "' is given to two different " + what + "s (their summary.json)");
		if (nameA != nameB && hashA == hashB)
			throw std::invalid_argument(
				"--pair: the same " + what + " is named both '" + nameA + "' and '" + nameB + "' (their summary.json)");
	};
	check("live run", a.live, a.liveHash, b.live, b.liveHash);
	check("map", a.map, a.mapHash, b.map, b.mapHash);
}

int run(int argc, char** argv)
{
	apps::CommandLine cli(
		"Draws the paper's Figures 7, 8 and 9 (McManus et al. 2014) as PNG through gnuplot from `shadyloc "
		"localise` output folders: per (live run, map) pair the baseline run (--localisers mono) and the "
		"combined run. Writes OUTDIR/figure7.png (one live run against one map), figure8.png (one live run "
		"against each of its maps) and figure9.png (blind distance after a failure, every pair pooled). "
		"Definitions: docs/figures.md.");
	auto& cmd = cli.cmd();
	TCLAP::MultiArg<std::string> pairs(
		"p", "pair",
		"a live run against a map: LIVE,MAP,BASELINE_DIR,COMBINED_DIR (names, then the two localise output "
		"folders; repeatable)",
		true, "live,map,dir,dir", cmd);
	TCLAP::ValueArg<std::string> fig7(
		"", "fig7", "the pair of Figure 7, LIVE,MAP (default: the first --pair)", false, "", "live,map", cmd);
	TCLAP::ValueArg<std::string> fig8(
		"", "fig8", "the live run of Figure 8 (default: the first --pair's)", false, "", "live", cmd);
	apps::NumberArg<double> markAt(
		cli, "", "blind-mark", "Figure 9 reports P(an episode reaches this distance) [m]", 100.0, "m", 0.0, 1e7);
	TCLAP::ValueArg<std::string> out(
		"o", "output", "existing directory for figure7.png, figure8.png, figure9.png", true, "", "dir", cmd);
	if (const auto rc = cli.parse(argc, argv)) return *rc;

	std::vector<TPairSpec> specs;
	for (const auto& s : pairs.getValue())
	{
		specs.push_back(parsePair(s));
		for (size_t i = 0; i + 1 < specs.size(); i++)
		{
			if (specs[i].live == specs.back().live && specs[i].map == specs.back().map)
				throw std::invalid_argument("--pair: " + specs.back().live + " against " + specs.back().map + " given twice");
			checkNames(specs[i], specs.back());
		}
	}
	const TPairSpec* p7 = &specs.front();
	if (fig7.isSet())
	{
		const auto f = splitCommas(fig7.getValue());
		if (f.size() != 2) throw std::invalid_argument("--fig7 '" + fig7.getValue() + "': expected LIVE,MAP");
		p7 = nullptr;
		for (const auto& s : specs)
			if (s.live == f[0] && s.map == f[1]) p7 = &s;
		if (!p7) throw std::invalid_argument("--fig7 '" + fig7.getValue() + "': no --pair of that live run and map");
	}
	const std::string live8 = fig8.isSet() ? fig8.getValue() : specs.front().live;
	std::vector<eval::TFigurePair> rows;
	for (const auto& s : specs)
		if (s.live == live8) rows.push_back({s.map, s.baselineCsv(), s.combinedCsv()});
	if (rows.empty()) throw std::invalid_argument("--fig8 '" + live8 + "': no --pair of that live run");
	if (!fs::is_directory(out.getValue()))
		throw std::invalid_argument("-o '" + out.getValue() + "': not an existing directory");

	// Figure 9 pools the episodes between two fixes of every pair.
	std::vector<double> base, comb;
	size_t gtRuns = 0, runs = 0;
	for (const auto& s : specs)
	{
		const auto b = eval::readFramesCsv(s.baselineCsv()), c = eval::readFramesCsv(s.combinedCsv());
		gtRuns += b.gt_distance + c.gt_distance;
		runs += 2;
		const auto lb = eval::blindEpisodeLengths(b), lc = eval::blindEpisodeLengths(c);
		base.insert(base.end(), lb.begin(), lb.end());
		comb.insert(comb.end(), lc.begin(), lc.end());
		std::cout << s.live << " against " << s.map << ": " << lb.size() << " baseline and " << lc.size()
				  << " combined blind episodes between fixes\n";
	}
	if (gtRuns != 0 && gtRuns != runs)
		throw std::invalid_argument(
			"the pairs mix runs localised with and without --gt: their distances (ground truth, VO) do not pool");

	io::OutputTransaction outputs;
	for (const auto& s : specs) outputs.addInput(s.baselineDir, "baseline run"), outputs.addInput(s.combinedDir, "combined run");
	const std::string dir = out.getValue();
	const std::string png7 = (fs::path(dir) / "figure7.png").string(), png8 = (fs::path(dir) / "figure8.png").string(),
					  png9 = (fs::path(dir) / "figure9.png").string();
	eval::figure7(p7->live, p7->map, p7->baselineCsv(), p7->combinedCsv(), outputs.addFile(png7, "figure 7"));
	eval::figure8(live8, rows, outputs.addFile(png8, "figure 8"));
	eval::figure9(base, comb, outputs.addFile(png9, "figure 9"), gtRuns ? "ground truth" : "VO", markAt.getValue());
	outputs.commit();
	std::cout << "wrote " << png7 << ", " << png8 << ", " << png9 << "\n";
	return 0;
}

apps::RegisterCommand reg(
	"figures", {"the paper's Figures 7-9 as PNG from localise outputs (-p LIVE,MAP,BASE_DIR,COMB_DIR ... -o DIR)", run});
}  // namespace cmd_figures
