/* ShadyLoc — Figures 7, 8 and 9 through gnuplot (docs/figures.md). */
#include <shadyloc/eval/Figures.h>
#include <shadyloc/io/AtomicFile.h>

#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iomanip>
#include <map>
#include <sstream>
#include <stdexcept>
#include <tuple>

namespace fs = std::filesystem;

namespace shadyloc::eval
{
namespace
{
// One palette for the figures and the render command's --localised snapshot.
constexpr const char* kMono = "#1f62c4";  // baseline / monochrome localiser
constexpr const char* kInvariant = "#e6820e";  // invariant localiser
constexpr const char* kBoth = "#2e9e44";
constexpr const char* kNeither = "#d62728";
constexpr const char* kOutside = "#dcdcdc";	 // frames outside the map
constexpr const char* kFalse = "#000000";

std::string where(const std::string& path, size_t line) { return "'" + path + "' line " + std::to_string(line); }

std::vector<std::string> splitFields(const std::string& line)
{
	std::vector<std::string> f;
	size_t a = 0;
	for (;;)
	{
		const size_t c = line.find(',', a);
		f.push_back(line.substr(a, c == std::string::npos ? std::string::npos : c - a));
		if (c == std::string::npos) break;
		a = c + 1;
	}
	return f;
}

double parseDouble(const std::string& s, const std::string& at, const std::string& column)
{
	char* end = nullptr;
	errno = 0;
	const double v = s.empty() ? NAN : std::strtod(s.c_str(), &end);
	if (s.empty() || end != s.c_str() + s.size() || errno == ERANGE || !std::isfinite(v))
		throw std::runtime_error(at + ": column '" + column + "': '" + s + "' is not a number");
	return v;
}

int parseInt(const std::string& s, const std::string& at, const std::string& column)
{
	const double v = parseDouble(s, at, column);
	if (v != std::floor(v) || std::fabs(v) > 2e9)
		throw std::runtime_error(at + ": column '" + column + "': '" + s + "' is not a whole number");
	return static_cast<int>(v);
}

/** 0/1, or -1 for an empty field when `emptyAllowed`. */
int parseFlag(const std::string& s, const std::string& at, const std::string& column, bool emptyAllowed)
{
	if (s.empty() && emptyAllowed) return -1;
	if (s == "0" || s == "1") return s == "1";
	throw std::runtime_error(at + ": column '" + column + "': '" + s + "' is not 0 or 1");
}

std::string fmt(double v, int decimals)
{
	std::ostringstream s;
	s << std::fixed << std::setprecision(decimals) << v;
	return s.str();
}

std::string pct(size_t a, size_t b) { return b ? fmt(100.0 * double(a) / double(b), 1) + " %" : "n/a"; }

/** The distance interval each frame stands for on a distance axis: from
 * half-way to the previous frame to half-way to the next one. */
std::vector<std::pair<double, double>> frameSpans(const TLocalisedRun& r)
{
	const auto& f = r.frames;
	std::vector<std::pair<double, double>> s(f.size());
	for (size_t i = 0; i < f.size(); i++)
	{
		s[i].first = i > 0 ? 0.5 * (f[i - 1].distance_m + f[i].distance_m) : f[i].distance_m;
		s[i].second = i + 1 < f.size() ? 0.5 * (f[i].distance_m + f[i + 1].distance_m) : f[i].distance_m;
	}
	return s;
}

/** Stretches of consecutive frames with the same key: [first, last] frames, key. */
template <typename Key>
std::vector<std::tuple<size_t, size_t, Key>> stretches(size_t n, const std::function<Key(size_t)>& key)
{
	std::vector<std::tuple<size_t, size_t, Key>> out;
	for (size_t i = 0; i < n; i++)
	{
		const Key k = key(i);
		if (!out.empty() && std::get<1>(out.back()) + 1 == i && std::get<2>(out.back()) == k)
			std::get<1>(out.back()) = i;
		else
			out.emplace_back(i, i, k);
	}
	return out;
}

/** The baseline and combined runs of one live run against one map. */
struct TPairRuns
{
	TLocalisedRun baseline, combined;
};

TPairRuns readPair(const std::string& baselineCsv, const std::string& combinedCsv)
{
	TPairRuns p{readFramesCsv(baselineCsv), readFramesCsv(combinedCsv)};
	const auto &b = p.baseline.frames, &c = p.combined.frames;
	if (p.baseline.gt_distance != p.combined.gt_distance)
		throw std::runtime_error(
			"'" + (p.baseline.gt_distance ? baselineCsv : combinedCsv) + "' was localised with --gt and '" +
			(p.baseline.gt_distance ? combinedCsv : baselineCsv) +
			"' without: their distances (ground truth, VO) do not compare");
	if (b.size() != c.size())
		throw std::runtime_error(
			"'" + combinedCsv + "' has " + std::to_string(c.size()) + " frames but '" + baselineCsv + "' has " +
			std::to_string(b.size()) + ": not the same live run");
	for (size_t i = 0; i < b.size(); i++)
		if (b[i].frame != c[i].frame || std::fabs(b[i].stamp - c[i].stamp) > 1e-6)
			throw std::runtime_error(
				"'" + combinedCsv + "' and '" + baselineCsv + "': row " + std::to_string(i + 1) + " is frame " +
				std::to_string(c[i].frame) + " at " + fmt(c[i].stamp, 6) + " s in one and frame " +
				std::to_string(b[i].frame) + " at " + fmt(b[i].stamp, 6) + " s in the other: not the same live run");
	for (const auto& f : b)
		if (f.used == "invariant" || f.used == "joint")
			throw std::runtime_error(
				"'" + baselineCsv + "' frame " + std::to_string(f.frame) +
				" used the " + f.used + " localiser: not a baseline run (localise --localisers mono)");
	if (p.combined.frames.front().invariant_ok < 0)
		throw std::runtime_error(
			"'" + combinedCsv + "': the invariant localiser did not run: not a combined run (localise without "
			"--localisers, or --localisers mono,invariant)");
	return p;
}

std::string distanceLabel(bool gt)
{
	return gt ? "distance travelled [m] (ground truth)" : "distance travelled [m] (visual odometry)";
}

/** "set object" rectangles shading the frames outside the map, behind everything. */
std::string outsideShading(const TLocalisedRun& r, double y0, double y1, int& objectId)
{
	const auto span = frameSpans(r);
	std::ostringstream g;
	for (const auto& [a, b, in] : stretches<bool>(r.frames.size(), [&](size_t i) { return r.frames[i].in_map; }))
	{
		if (in) continue;
		// A lone frame at the run's end spans nothing: give it half its neighbour's step.
		double x0 = span[a].first, x1 = span[b].second;
		if (x1 - x0 < 1e-9) x1 = x0 + 1e-3;
		g << "set object " << objectId++ << " rect from " << x0 << "," << y0 << " to " << x1 << "," << y1
		  << " fc rgb '" << kOutside << "' fs solid 1.0 noborder behind\n";
	}
	return g.str();
}

/** Text as a gnuplot double-quoted string: a '\n' breaks the line,
 * backslashes and quotes are escaped. */
std::string gnuplotText(const std::string& text)
{
	std::string t = "\"";
	for (const char c : text)
	{
		if (c == '\n') t += "\\n";
		else if (c == '"' || c == '\\') t += std::string("\\") + c;
		else if (c == '\r') throw std::invalid_argument("a label with a carriage return: '" + text + "'");
		else t += c;
	}
	return t + "\"";
}

/** Row labels left of the plot, left-justified from the image's left edge
 * (gnuplot right-justifies tic labels by an estimate of their width, which
 * lets long proportional-font labels run under the plot), and a left margin
 * that holds them (about 7 px a character at 'sans,10'). */
std::string rowLabels(const std::vector<std::string>& labels, const std::vector<double>& ys, unsigned width)
{
	size_t n = 0;
	for (const auto& l : labels)
		for (size_t a = 0, b; a <= l.size(); a = b + 1)
		{
			b = std::min(l.find('\n', a), l.size());
			n = std::max(n, b - a);
		}
	std::ostringstream g;
	g << "set ytics (";
	for (size_t i = 0; i < ys.size(); i++) g << (i ? ", " : "") << "'' " << ys[i];
	g << ")\nset lmargin at screen " << std::min(0.6, (7.0 * double(n) + 24.0) / width) << "\n";
	for (size_t i = 0; i < labels.size(); i++)
		g << "set label " << 100 + i << " " << gnuplotText(labels[i]) << " at screen " << 10.0 / width << ", first "
		  << ys[i] << " left\n";
	return g.str();
}

std::string datablock(const std::string& name, const std::string& rows)
{
	return "$" + name + " << EOD\n" + rows + "EOD\n";
}
}  // namespace

// ---------------------------------------------------------------- frames.csv

TLocalisedRun readFramesCsv(const std::string& path)
{
	std::ifstream in(path);
	if (!in) throw std::runtime_error("'" + path + "': cannot open (a frames.csv of shadyloc localise?)");
	TLocalisedRun run;
	run.path = path;
	std::string line;
	if (!std::getline(in, line)) throw std::runtime_error(where(path, 1) + ": empty file, expected a header");
	if (!line.empty() && line.back() == '\r') line.pop_back();
	const auto header = splitFields(line);
	std::map<std::string, size_t> col;
	for (size_t i = 0; i < header.size(); i++) col.emplace(header[i], i);
	auto need = [&](const std::string& name) {
		const auto it = col.find(name);
		if (it == col.end())
			throw std::runtime_error(
				where(path, 1) + ": no column '" + name + "' in the header (a frames.csv of shadyloc localise?)");
		return it->second;
	};
	const size_t cFrame = need("frame"), cStamp = need("stamp"), cDist = need("distance_m"), cIn = need("in_map"),
				 cMono = need("mono_ok"), cInv = need("invariant_ok"), cUsed = need("used");
	const auto itGt = col.find("gt_distance_m"), itTrue = col.find("used_true");
	run.gt_distance = itGt != col.end();
	size_t lineNo = 1;
	while (std::getline(in, line))
	{
		lineNo++;
		if (!line.empty() && line.back() == '\r') line.pop_back();
		if (line.empty()) continue;
		const std::string at = where(path, lineNo);
		const auto f = splitFields(line);
		if (f.size() != header.size())
			throw std::runtime_error(
				at + ": " + std::to_string(f.size()) + " fields, the header has " + std::to_string(header.size()));
		TLocalisedFrame r;
		r.frame = parseInt(f[cFrame], at, "frame");
		r.stamp = parseDouble(f[cStamp], at, "stamp");
		r.distance_m = parseDouble(run.gt_distance ? f[itGt->second] : f[cDist], at, run.gt_distance ? "gt_distance_m" : "distance_m");
		r.in_map = parseFlag(f[cIn], at, "in_map", false) == 1;
		r.mono_ok = parseFlag(f[cMono], at, "mono_ok", true);
		r.invariant_ok = parseFlag(f[cInv], at, "invariant_ok", true);
		r.used = f[cUsed];
		if (r.used != "mono" && r.used != "invariant" && r.used != "joint" && r.used != "none")
			throw std::runtime_error(at + ": column 'used': '" + r.used + "' is not mono, invariant, joint or none");
		if (itTrue != col.end()) r.used_true = parseFlag(f[itTrue->second], at, "used_true", true);
		if (!run.frames.empty() && r.distance_m < run.frames.back().distance_m - 1e-9)
			throw std::runtime_error(at + ": the distance travelled decreases (" + fmt(run.frames.back().distance_m, 3) +
									 " m, then " + fmt(r.distance_m, 3) + " m)");
		run.frames.push_back(std::move(r));
	}
	if (run.frames.empty()) throw std::runtime_error("'" + path + "': no frames (a header only)");
	return run;
}

std::vector<TBlindEpisode> blindEpisodesOf(const TLocalisedRun& run)
{
	std::vector<bool> fix;
	std::vector<double> dist;
	for (const auto& f : run.frames) fix.push_back(f.fix()), dist.push_back(f.distance_m);
	return blindEpisodes(fix, dist);
}

std::vector<double> blindEpisodeLengths(const TLocalisedRun& run)
{
	std::vector<double> l;
	for (const auto& e : blindEpisodesOf(run))
		if (e.kind == TBlindEpisode::Between) l.push_back(e.length_m);
	return l;
}

FixHolder fixHolder(const TLocalisedFrame& b, const TLocalisedFrame& c)
{
	const bool base = b.fix(), inv = c.invariant_ok == 1;
	return base ? (inv ? FixHolder::Both : FixHolder::BaselineOnly) : (inv ? FixHolder::InvariantOnly : FixHolder::Neither);
}

// ---------------------------------------------------------------- gnuplot

std::string gnuplotQuote(const std::string& text)
{
	std::string q = "'";
	for (const char c : text)
	{
		if (c == '\n' || c == '\r') throw std::invalid_argument("gnuplotQuote: a line break in '" + text + "'");
		q += c;
		if (c == '\'') q += '\'';
	}
	return q + "'";
}

void runGnuplot(const std::string& body, const std::string& pngPath, unsigned width, unsigned height)
{
	if (width < 16 || height < 16) throw std::invalid_argument("'" + pngPath + "': figure size below 16 px");
	// The script goes to a private temporary file (gnuplot's messages name its lines).
	std::string scriptPath = (fs::temp_directory_path() / "shadyloc-gnuplot-XXXXXX.gp").string();
	const int fd = mkstemps(scriptPath.data(), 3);
	if (fd < 0) throw std::runtime_error("cannot make a temporary file for gnuplot's script in " + fs::temp_directory_path().string());
	close(fd);
	struct Remove
	{
		std::string path;
		~Remove()
		{
			std::error_code ec;
			fs::remove(path, ec);
		}
	} removeScript{scriptPath};
	io::writeAtomically(pngPath, [&](const std::string& tmp) {
		{
			std::ofstream s(scriptPath);
			s << "set terminal pngcairo size " << width << "," << height << " font 'sans,10' noenhanced\n"
			  << "set output " << gnuplotQuote(tmp) << "\n"
			  << body << "\nunset output\n";
			s.close();
			if (!s) throw std::runtime_error("cannot write gnuplot's script '" + scriptPath + "'");
		}
		const std::string cmd = "gnuplot " + gnuplotQuote(scriptPath) + " 2>&1";  // sh quoting: no quote in the name
		std::string output;
		FILE* p = popen(cmd.c_str(), "r");
		if (!p) throw std::runtime_error("cannot start gnuplot to draw '" + pngPath + "'");
		char buf[512];
		while (fgets(buf, sizeof buf, p)) output += buf;
		const int rc = pclose(p);
		if (rc != 0)
		{
			if (WIFEXITED(rc) && WEXITSTATUS(rc) == 127)
				throw std::runtime_error(
					"gnuplot is needed to draw '" + pngPath +
					"' (Debian package gnuplot-nox, installed by scripts/setup.sh)");
			throw std::runtime_error("gnuplot failed drawing '" + pngPath + "':\n" + output);
		}
		std::error_code ec;
		if (!fs::is_regular_file(tmp) || fs::file_size(tmp, ec) == 0)
			throw std::runtime_error("gnuplot wrote no image for '" + pngPath + "':\n" + output);
	});
}

// ---------------------------------------------------------------- Figure 7

void figure7(
	const std::string& liveName, const std::string& mapName, const std::string& baselineCsv,
	const std::string& combinedCsv, const std::string& pngPath)
{
	const TPairRuns p = readPair(baselineCsv, combinedCsv);
	const auto &B = p.baseline.frames, &C = p.combined.frames;
	const bool gt = p.baseline.gt_distance && p.combined.gt_distance;
	// Counts for the row labels: fixes over the in-map frames.
	size_t inMap = 0, nBase = 0, nInv = 0, nComb = 0, falseB = 0, falseC = 0;
	std::ostringstream base, inv, combMono, combInv, falses;
	base << std::fixed << std::setprecision(3);
	for (auto* s : {&inv, &combMono, &combInv, &falses}) *s << std::fixed << std::setprecision(3);
	for (size_t i = 0; i < C.size(); i++)
	{
		const double x = C[i].distance_m;
		inMap += C[i].in_map;
		if (B[i].fix())
		{
			base << x << " 3\n";
			nBase += C[i].in_map;
			if (B[i].used_true == 0) falses << x << " 3\n", falseB++;
		}
		if (C[i].invariant_ok == 1)
		{
			inv << x << " 2\n";
			nInv += C[i].in_map;
		}
		if (C[i].fix())
		{
			(C[i].used == "mono" ? combMono : combInv) << x << " 1\n";
			nComb += C[i].in_map;
			if (C[i].used_true == 0) falses << x << " 1\n", falseC++;
		}
	}
	const double x0 = C.front().distance_m, x1 = std::max(C.back().distance_m, x0 + 1.0);
	const std::vector<std::string> labels = {
		"combined: " + pct(nComb, inMap), "invariant localiser: " + pct(nInv, inMap), "baseline: " + pct(nBase, inMap)};
	std::ostringstream g;
	g << std::setprecision(10);
	g << datablock("base", base.str()) << datablock("inv", inv.str()) << datablock("combmono", combMono.str())
	  << datablock("combinv", combInv.str()) << datablock("false", falses.str());
	g << "set title " << gnuplotQuote("Figure 7: live run " + liveName + " against the map of " + mapName + " (fixes over in-map frames)") << "\n"
	  << "set xlabel " << gnuplotQuote(distanceLabel(gt)) << " offset 0,0.4\n"
	  << "set xrange [" << x0 << ":" << x1 << "]\nset yrange [0.4:3.6]\n"
	  << rowLabels(labels, {1, 2, 3}, 1000)
	  << "set grid xtics\nset border 3\nset xtics nomirror\nset ytics nomirror scale 0\n"
	  << "set key outside right center vertical Left reverse samplen 1\n";
	int obj = 1;
	g << outsideShading(p.combined, 0.4, 3.6, obj);
	const std::string falseTitle = gt ? "false fix (" + std::to_string(falseB) + " baseline, " +
											std::to_string(falseC) + " combined)"
									  : "";
	g << "plot NaN with boxes fs solid 1.0 noborder lc rgb '" << kOutside
	  << "' title 'outside the map', "
	  << "$base using 1:2 with points pt 7 ps 0.7 lc rgb '" << kMono << "' title 'mono fix', "
	  << "$combmono using 1:2 with points pt 7 ps 0.7 lc rgb '" << kMono << "' notitle, "
	  << "$inv using 1:2 with points pt 7 ps 0.7 lc rgb '" << kInvariant << "' title 'invariant fix', "
	  << "$combinv using 1:2 with points pt 7 ps 0.7 lc rgb '" << kInvariant << "' notitle";
	if (gt) g << ", $false using 1:2 with points pt 2 ps 1.4 lw 2 lc rgb '" << kFalse << "' title " << gnuplotQuote(falseTitle);
	g << "\n";
	try
	{
		runGnuplot(g.str(), pngPath, 1000, 360);
	}
	catch (const std::exception& e)
	{
		throw std::runtime_error("figure 7 (" + liveName + " against " + mapName + "): " + e.what());
	}
}

// ---------------------------------------------------------------- Figure 8

void figure8(const std::string& liveName, const std::vector<TFigurePair>& pairs, const std::string& pngPath)
{
	if (pairs.empty()) throw std::invalid_argument("figure 8 of " + liveName + ": no maps");
	constexpr unsigned kWidth8 = 1100;
	const int n = static_cast<int>(pairs.size());
	std::ostringstream segs, outside;
	segs << std::setprecision(10);
	outside << std::setprecision(10);
	double x0 = 1e300, x1 = -1e300;
	bool gt = true;
	const char* colour[] = {kBoth, kMono, kInvariant, kNeither};
	std::vector<std::string> labels;
	std::vector<double> ys;
	std::array<double, 4> metres{};
	for (int r = 0; r < n; r++)
	{
		const auto& pr = pairs[r];
		const TPairRuns p = readPair(pr.baselineCsv, pr.combinedCsv);
		gt &= p.baseline.gt_distance && p.combined.gt_distance;
		const auto &B = p.baseline.frames, &C = p.combined.frames;
		const auto span = frameSpans(p.combined);
		x0 = std::min(x0, C.front().distance_m);
		x1 = std::max(x1, C.back().distance_m);
		const double y = n - r;	 // first map on top
		for (const auto& [a, b, h] :
			 stretches<FixHolder>(C.size(), [&](size_t i) { return fixHolder(B[i], C[i]); }))
		{
			const int k = static_cast<int>(h);
			segs << 0.5 * (span[a].first + span[b].second) << ' ' << y << ' ' << span[a].first << ' ' << span[b].second
				 << ' ' << y - 0.3 << ' ' << y + 0.3 << ' ' << k << '\n';
			metres[k] += span[b].second - span[a].first;
		}
		for (const auto& [a, b, in] : stretches<bool>(C.size(), [&](size_t i) { return C[i].in_map; }))
			if (!in)
				outside << 0.5 * (span[a].first + span[b].second) << ' ' << y << ' ' << span[a].first << ' '
						<< span[b].second << ' ' << y - 0.42 << ' ' << y - 0.34 << '\n';
		size_t inMap = 0, nb = 0, nc = 0;
		for (size_t i = 0; i < C.size(); i++)
			inMap += C[i].in_map, nb += C[i].in_map && B[i].fix(), nc += C[i].in_map && C[i].fix();
		labels.push_back("map " + pr.mapName + "\nbaseline " + pct(nb, inMap) + ", combined " + pct(nc, inMap));
		ys.push_back(y);
	}
	x1 = std::max(x1, x0 + 1.0);
	const double total = metres[0] + metres[1] + metres[2] + metres[3];
	auto share = [&](int k) { return total > 0 ? " (" + fmt(100 * metres[k] / total, 1) + " %)" : std::string(); };
	std::ostringstream g;
	g << datablock("segs", segs.str()) << datablock("outside", outside.str() + (outside.str().empty() ? "NaN NaN NaN NaN NaN NaN\n" : ""));
	g << "set title " << gnuplotQuote("Figure 8: live run " + liveName + " against each map (coverage over in-map frames)") << "\n"
	  << "set xlabel " << gnuplotQuote(distanceLabel(gt)) << " offset 0,0.4\n"
	  << "set xrange [" << std::setprecision(10) << x0 << ":" << x1 << "]\nset yrange [0.4:" << n + 0.6 << "]\n"
	  << rowLabels(labels, ys, kWidth8) << "set ytics nomirror scale 0\nset xtics nomirror\nset border 3\n"
	  << "set grid xtics\nset key outside right center vertical Left reverse samplen 2\n"
	  << "set palette defined (0 '" << colour[0] << "', 1 '" << colour[1] << "', 2 '" << colour[2] << "', 3 '"
	  << colour[3] << "')\nset cbrange [0:3]\nunset colorbox\n";
	g << "plot $segs using 1:2:3:4:5:6:7 with boxxyerror fs solid 1.0 noborder lc palette notitle, "
	  << "$outside using 1:2:3:4:5:6 with boxxyerror fs solid 1.0 noborder lc rgb '#606060' "
		 "title 'outside the map (under the row)'";
	const char* names[] = {"both", "baseline only", "invariant only", "neither"};
	for (int k = 0; k < 4; k++)
		g << ", NaN with boxes fs solid 1.0 noborder lc rgb '" << colour[k] << "' title "
		  << gnuplotQuote(std::string(names[k]) + share(k));
	g << "\n";
	try
	{
		runGnuplot(g.str(), pngPath, kWidth8, static_cast<unsigned>(std::max(200, 130 + 45 * n)));
	}
	catch (const std::exception& e)
	{
		throw std::runtime_error("figure 8 (" + liveName + "): " + e.what());
	}
}

// ---------------------------------------------------------------- Figure 9

void figure9(
	const std::vector<double>& baseline, const std::vector<double>& combined, const std::string& pngPath,
	const std::string& distanceFrom, double markAt_m)
{
	for (const auto* v : {&baseline, &combined})
		for (const double l : *v)
			if (!std::isfinite(l) || l < 0)
				throw std::invalid_argument("figure 9: an episode length of " + std::to_string(l) + " m");
	double xmax = 1.0;
	for (const auto* v : {&baseline, &combined})
		for (const double l : *v) xmax = std::max(xmax, 1.05 * l);
	// P(L >= d): 1 up to the shortest episode, then a step down at each length.
	auto curve = [&](std::vector<double> l) {
		std::sort(l.begin(), l.end());
		std::ostringstream s;
		s << std::setprecision(10) << "0 1\n";
		const double n = double(l.size());
		for (size_t k = 0; k < l.size(); k++)
			s << l[k] << ' ' << (n - double(k)) / n << '\n' << l[k] << ' ' << (n - double(k) - 1) / n << '\n';
		s << xmax << " 0\n";
		return l.empty() ? std::string("NaN NaN\n") : s.str();
	};
	auto legend = [&](const std::string& name, const std::vector<double>& l) {
		if (l.empty()) return name + ": no episodes";
		const size_t k = static_cast<size_t>(std::count_if(l.begin(), l.end(), [&](double x) { return x >= markAt_m; }));
		return name + ": " + std::to_string(l.size()) + (l.size() == 1 ? " episode" : " episodes") + ", P(>= " +
			   fmt(markAt_m, 0) + " m) = " + fmt(double(k) / double(l.size()), 3);
	};
	std::ostringstream g;
	g << datablock("base", curve(baseline)) << datablock("comb", curve(combined));
	g << "set title 'Figure 9: probability of travelling a given distance blind after a localisation failure'\n"
	  << "set xlabel " << gnuplotQuote("distance travelled without a fix d [m] (" + distanceFrom + ")") << "\n"
	  << "set ylabel 'P(blind episode >= d)'\n"
	  << "set xrange [0:" << std::setprecision(10) << xmax << "]\nset yrange [0:1.05]\n"
	  << "set grid\nset key top right box opaque\nset border 3\nset xtics nomirror\nset ytics nomirror\n";
	if (markAt_m > 0 && markAt_m <= xmax)
		g << "set arrow 1 from " << markAt_m << ", graph 0 to " << markAt_m
		  << ", graph 1 nohead lc rgb '#808080' dt 2 lw 1.5\n";
	g << "plot $base using 1:2 with lines lw 2.5 lc rgb '" << kMono << "' title " << gnuplotQuote(legend("baseline", baseline))
	  << ", $comb using 1:2 with lines lw 2.5 lc rgb '" << kBoth << "' title " << gnuplotQuote(legend("combined", combined))
	  << "\n";
	try
	{
		runGnuplot(g.str(), pngPath, 800, 500);
	}
	catch (const std::exception& e)
	{
		throw std::runtime_error(std::string("figure 9: ") + e.what());
	}
}

}  // namespace shadyloc::eval
