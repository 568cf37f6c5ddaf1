/* ShadyLoc — the job records of the leave-one-out evaluation. */
#include "EvalRecords.h"

#include <shadyloc/io/AtomicFile.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <map>
#include <sstream>
#include <stdexcept>

namespace shadyloc::eval
{
namespace
{
std::string g17(double v)
{
	char b[40];
	std::snprintf(b, sizeof b, "%.17g", v);
	return b;
}

/** Lines "key<TAB>v1<TAB>v2..." after a header line; each key's handler. */
class RecordReader
{
   public:
	RecordReader(const std::string& path, const std::string& header) : m_path(path), m_in(path)
	{
		if (!m_in) throw std::runtime_error("'" + path + "' cannot be read");
		std::string first;
		std::getline(m_in, first);
		if (first != header)
			throw std::runtime_error(path + ":1: expected '" + header + "', found '" + first.substr(0, 60) + "'");
	}
	/** Every key but those in `repeatable` may appear once. */
	void read(const std::map<std::string, std::pair<size_t, std::function<void(const std::vector<std::string>&)>>>& keys,
			  const std::vector<std::string>& required,
			  const std::vector<std::string>& repeatable = {"channel", "fix_error", "episode"})
	{
		std::map<std::string, int> seen;
		std::string line;
		for (m_line = 2; std::getline(m_in, line); m_line++)
		{
			if (line.empty()) continue;
			std::vector<std::string> f;
			std::istringstream s(line);
			for (std::string w; std::getline(s, w, '\t');) f.push_back(w);
			const auto it = keys.find(f[0]);
			if (it == keys.end()) fail("unknown key '" + f[0] + "'");
			if (f.size() != it->second.first + 1)
				fail("'" + f[0] + "' has " + std::to_string(f.size() - 1) + " values, expected " +
					 std::to_string(it->second.first));
			if (seen[f[0]]++ && std::find(repeatable.begin(), repeatable.end(), f[0]) == repeatable.end())
				fail("'" + f[0] + "' given twice");
			it->second.second(std::vector<std::string>(f.begin() + 1, f.end()));
		}
		for (const auto& k : required)
			if (!seen.count(k)) throw std::runtime_error(m_path + ": no '" + k + "' line (a truncated record?)");
	}
	[[noreturn]] void fail(const std::string& why) const
	{
		throw std::runtime_error(m_path + ":" + std::to_string(m_line) + ": " + why);
	}
	size_t count(const std::string& s) const
	{
		size_t v = 0;
		const auto r = std::from_chars(s.data(), s.data() + s.size(), v);
		if (r.ec != std::errc() || r.ptr != s.data() + s.size()) fail("'" + s + "' is not a count");
		return v;
	}
	double number(const std::string& s) const
	{
		char* end = nullptr;
		const double v = std::strtod(s.c_str(), &end);
		if (s.empty() || end != s.c_str() + s.size()) fail("'" + s + "' is not a number");
		return v;
	}

   private:
	std::string m_path;
	std::ifstream m_in;
	int m_line = 1;
};

/** Throws "<path>: <what> <why>" unless `ok`. */
void require(bool ok, const std::string& path, const std::string& why)
{
	if (!ok) throw std::runtime_error(path + ": " + why + " (a damaged or edited record)");
}

std::string n2s(size_t v) { return std::to_string(v); }

bool isLength(double v) { return std::isfinite(v) && v >= 0; }

/** What a map job's counts must satisfy among themselves. */
void checkMapRecord(const TMapRecord& r, const std::string& path)
{
	require(r.keyframes <= r.frames, path, "keyframes " + n2s(r.keyframes) + " > frames " + n2s(r.frames));
	require(r.gt_keyframes <= r.keyframes, path, "gt_keyframes " + n2s(r.gt_keyframes) + " > keyframes " + n2s(r.keyframes));
	require(isLength(r.path_m), path, "path_m is not a length >= 0");
}

/** A channel's counts: each a subset of the one before (accepted of the
 * frames, used and in-map of accepted, true of in-map). */
void checkPairChannel(const TPairChannel& c, const TPairRecord& r, const std::string& path)
{
	const std::string ch = "channel '" + c.name + "': ";
	require(c.accepted <= r.frames, path, ch + "accepted " + n2s(c.accepted) + " > frames " + n2s(r.frames));
	require(c.used <= c.accepted, path, ch + "used " + n2s(c.used) + " > accepted " + n2s(c.accepted));
	require(c.accepted_in_map <= c.accepted && c.accepted_in_map <= r.in_map_frames, path,
		ch + "accepted_in_map " + n2s(c.accepted_in_map) + " exceeds accepted or in_map_frames (coverage above 100 %)");
	require(c.true_in_map <= c.accepted_in_map, path, ch + "true_in_map exceeds accepted_in_map");
	require(c.true_fixes + c.false_fixes + c.unverifiable <= c.accepted, path, ch + "true + false + unverifiable > accepted");
}

/** What a pair job's numbers must satisfy: coverage within [0, 100] %,
 * counts consistent with each other, lengths finite and >= 0. */
void checkPairRecord(const TPairRecord& r, const std::string& path)
{
	require(r.in_map_frames <= r.frames, path, "in_map_frames " + n2s(r.in_map_frames) + " > frames " + n2s(r.frames));
	require(r.fixes <= r.frames, path, "fixes " + n2s(r.fixes) + " > frames " + n2s(r.frames));
	require(r.fixes_in_map <= r.fixes && r.fixes_in_map <= r.in_map_frames, path,
		"fixes_in_map " + n2s(r.fixes_in_map) + " exceeds fixes or in_map_frames (coverage above 100 %)");
	require(r.true_fixes_in_map <= r.fixes_in_map && r.true_fixes_in_map <= r.true_fixes, path,
		"true_fixes_in_map exceeds fixes_in_map or true_fixes");
	require(r.true_fixes + r.false_fixes + r.unverifiable <= r.fixes, path, "true + false + unverifiable fixes > fixes");
	require(r.ground_truth || r.true_fixes + r.false_fixes == 0, path, "true or false fixes without ground truth");
	require(r.first_fix_frame >= -1 && (r.first_fix_frame < 0 || size_t(r.first_fix_frame) < r.frames), path,
		"first_fix_frame " + std::to_string(r.first_fix_frame) + " outside -1.." + std::to_string(long(r.frames) - 1));
	require(isLength(r.total_m) && isLength(r.blind_m), path, "total_m and blind_m must be lengths >= 0");
	require(r.before_first_fix_m == -1 || isLength(r.before_first_fix_m), path, "before_first_fix_m is neither -1 nor >= 0");
	for (const auto& c : r.channels) checkPairChannel(c, r, path);
	for (size_t b = 0; b < r.bins.size(); b++)
		require(r.bins[b] <= r.in_map_frames && (b == 0 || r.bins[b - 1] <= r.bins[b]), path,
			"accuracy bins " + n2s(r.bins[0]) + ", " + n2s(r.bins[1]) + ", " + n2s(r.bins[2]) +
				": each within in_map_frames, the wider ones holding the narrower");
	require(r.fix_errors.size() <= r.fixes, path, "more fix errors than fixes");
	for (const auto& e : r.fix_errors)
		require(isLength(e[0]) && isLength(e[1]) && e[1] <= 180, path, "fix error outside [0, inf) m x [0, 180] deg");
	double episodes = 0;
	for (const auto& e : r.episodes)
	{
		require(isLength(e.second), path, "episode length is not a length >= 0");
		episodes += e.second;
	}
	require(std::fabs(episodes - r.blind_m) <= 1e-6 * std::max(1.0, r.blind_m), path,
		"blind_m is not the sum of the episodes' lengths");
}

const std::string kMapHeader = "# shadyloc eval map v" + std::to_string(kPlanVersion);
const std::string kPairHeader = "# shadyloc eval pair v" + std::to_string(kPlanVersion);
}  // namespace

const TPairChannel* TPairRecord::channel(const std::string& name) const
{
	for (const auto& c : channels)
		if (c.name == name) return &c;
	return nullptr;
}

TPairRecord makePairRecord(
	const std::string& live, const std::string& map, EvalSystem system,
	const Updates& ups, const TEvaluation& ev)
{
	TPairRecord r;
	r.live = live;
	r.map = map;
	r.system = toString(system);
	for (const auto& l : localisersOf(system)) r.localisers += (r.localisers.empty() ? "" : ",") + l;
	r.frames = ups.size();
	r.ground_truth = ev.ground_truth;
	r.in_map_frames = ev.in_map_frames;
	r.fixes = ev.fixes;
	r.fixes_in_map = ev.fixes_in_map;
	r.true_fixes = ev.true_fixes;
	r.true_fixes_in_map = ev.true_fixes_in_map;
	r.false_fixes = ev.false_fixes;
	r.unverifiable = ev.unverifiable;
	r.total_m = ev.total_m;
	r.blind_m = ev.blind_m;
	r.before_first_fix_m = ev.before_first_fix_m;
	r.first_fix_frame = ev.first_fix_frame;
	r.global_searches = ev.global_searches;
	for (size_t c = 0; c < ev.channels.size(); c++)
	{
		const auto& s = ev.channels[c];
		TPairChannel pc;
		pc.name = s.channel;
		pc.accepted = s.accepted;
		pc.used = s.used;
		pc.true_fixes = s.true_fixes;
		pc.false_fixes = s.false_fixes;
		pc.unverifiable = s.unverifiable;
		for (size_t i = 0; i < ups.size(); i++)
		{
			if (!ev.frames[i].in_map || c >= ups[i].localisers.size() || !ups[i].localisers[c].accepted()) continue;
			pc.accepted_in_map++;
			pc.true_in_map += c < ev.frames[i].channel.size() && ev.frames[i].channel[c] == FixTruth::True;
		}
		r.channels.push_back(pc);
	}
	for (const auto& f : ev.frames)
	{
		if (f.used_err_m < 0) continue;	 // no fix, or no truth to check it against
		r.fix_errors.push_back({f.used_err_m, f.used_err_deg});
		if (!f.in_map) continue;
		for (size_t b = 0; b < kAccuracyBins.size(); b++)
			r.bins[b] += f.used_err_m <= kAccuracyBins[b][0] && f.used_err_deg <= kAccuracyBins[b][1];
	}
	for (const auto& e : ev.episodes) r.episodes.push_back({toString(e.kind), e.length_m});
	return r;
}

void writeMapRecord(const std::string& path, const TMapRecord& r)
{
	std::ostringstream s;
	s << kMapHeader << "\nrun\t" << r.run << "\nframes\t" << r.frames << "\nkeyframes\t" << r.keyframes
	  << "\ngt_keyframes\t" << r.gt_keyframes << "\nbreaks\t" << r.breaks << "\npath_m\t" << g17(r.path_m) << "\n";
	io::writeTextFile(path, s.str());
}

TMapRecord readMapRecord(const std::string& path)
{
	TMapRecord r;
	RecordReader rd(path, kMapHeader);
	rd.read(
		{{"run", {1, [&](const auto& v) { r.run = v[0]; }}},
		 {"frames", {1, [&](const auto& v) { r.frames = rd.count(v[0]); }}},
		 {"keyframes", {1, [&](const auto& v) { r.keyframes = rd.count(v[0]); }}},
		 {"gt_keyframes", {1, [&](const auto& v) { r.gt_keyframes = rd.count(v[0]); }}},
		 {"breaks", {1, [&](const auto& v) { r.breaks = rd.count(v[0]); }}},
		 {"path_m", {1, [&](const auto& v) { r.path_m = rd.number(v[0]); }}}},
		{"run", "frames", "keyframes", "gt_keyframes", "breaks", "path_m"});
	checkMapRecord(r, path);
	return r;
}

void writePairRecord(const std::string& path, const TPairRecord& r)
{
	std::ostringstream s;
	s << kPairHeader << "\nlive\t" << r.live << "\nmap\t" << r.map << "\nsystem\t" << r.system << "\nlocalisers\t"
	  << r.localisers << "\nframes\t" << r.frames << "\nground_truth\t" << int(r.ground_truth) << "\nin_map_frames\t"
	  << r.in_map_frames << "\nfixes\t" << r.fixes << "\nfixes_in_map\t" << r.fixes_in_map << "\ntrue_fixes\t"
	  << r.true_fixes << "\ntrue_fixes_in_map\t" << r.true_fixes_in_map << "\nfalse_fixes\t" << r.false_fixes
	  << "\nunverifiable\t" << r.unverifiable << "\ntotal_m\t" << g17(r.total_m) << "\nblind_m\t" << g17(r.blind_m)
	  << "\nbefore_first_fix_m\t" << g17(r.before_first_fix_m) << "\nfirst_fix_frame\t" << r.first_fix_frame
	  << "\nglobal_searches\t" << r.global_searches << "\n";
	for (const auto& c : r.channels)
		s << "channel\t" << c.name << '\t' << c.accepted << '\t' << c.used << '\t' << c.accepted_in_map << '\t'
		  << c.true_fixes << '\t' << c.true_in_map << '\t' << c.false_fixes << '\t' << c.unverifiable << "\n";
	s << "bins\t" << r.bins[0] << '\t' << r.bins[1] << '\t' << r.bins[2] << "\n";
	for (const auto& e : r.fix_errors) s << "fix_error\t" << g17(e[0]) << '\t' << g17(e[1]) << "\n";
	for (const auto& e : r.episodes) s << "episode\t" << e.first << '\t' << g17(e.second) << "\n";
	s << "end\n";  // a record cut short lacks it
	io::writeTextFile(path, s.str());
}

TPairRecord readPairRecord(const std::string& path)
{
	TPairRecord r;
	RecordReader rd(path, kPairHeader);
	const auto cnt = [&](size_t& x) { return std::make_pair(size_t(1), std::function<void(const std::vector<std::string>&)>([&](const auto& v) { x = rd.count(v[0]); })); };
	const auto numb = [&](double& x) { return std::make_pair(size_t(1), std::function<void(const std::vector<std::string>&)>([&](const auto& v) { x = rd.number(v[0]); })); };
	const auto str = [&](std::string& x) { return std::make_pair(size_t(1), std::function<void(const std::vector<std::string>&)>([&](const auto& v) { x = v[0]; })); };
	size_t gt = 0;
	double firstFix = -1;
	rd.read(
		{{"live", str(r.live)},
		 {"map", str(r.map)},
		 {"system", str(r.system)},
		 {"localisers", str(r.localisers)},
		 {"frames", cnt(r.frames)},
		 {"ground_truth", cnt(gt)},
		 {"in_map_frames", cnt(r.in_map_frames)},
		 {"fixes", cnt(r.fixes)},
		 {"fixes_in_map", cnt(r.fixes_in_map)},
		 {"true_fixes", cnt(r.true_fixes)},
		 {"true_fixes_in_map", cnt(r.true_fixes_in_map)},
		 {"false_fixes", cnt(r.false_fixes)},
		 {"unverifiable", cnt(r.unverifiable)},
		 {"total_m", numb(r.total_m)},
		 {"blind_m", numb(r.blind_m)},
		 {"before_first_fix_m", numb(r.before_first_fix_m)},
		 {"first_fix_frame", numb(firstFix)},
		 {"global_searches", cnt(r.global_searches)},
		 {"channel",
		  {8,
		   [&](const auto& v) {
			   TPairChannel c;
			   c.name = v[0];
			   c.accepted = rd.count(v[1]);
			   c.used = rd.count(v[2]);
			   c.accepted_in_map = rd.count(v[3]);
			   c.true_fixes = rd.count(v[4]);
			   c.true_in_map = rd.count(v[5]);
			   c.false_fixes = rd.count(v[6]);
			   c.unverifiable = rd.count(v[7]);
			   r.channels.push_back(c);
		   }}},
		 {"bins",
		  {3,
		   [&](const auto& v) {
			   for (size_t b = 0; b < 3; b++) r.bins[b] = rd.count(v[b]);
		   }}},
		 {"fix_error", {2, [&](const auto& v) { r.fix_errors.push_back({rd.number(v[0]), rd.number(v[1])}); }}},
		 {"episode",
		  {2,
		   [&](const auto& v) {
			   if (v[0] != "between" && v[0] != "at_end" && v[0] != "before_first_fix")
				   rd.fail("episode kind '" + v[0] + "'");
			   r.episodes.push_back({v[0], rd.number(v[1])});
		   }}},
		 {"end", {0, [](const auto&) {}}}},
		{"live", "map", "system", "frames", "ground_truth", "in_map_frames", "channel", "bins", "end"});
	if (gt > 1) throw std::runtime_error(path + ": ground_truth " + std::to_string(gt) + " is neither 0 nor 1");
	if (!(firstFix >= -1 && firstFix <= 2e9 && firstFix == std::floor(firstFix)))
		throw std::runtime_error(path + ": first_fix_frame is not a frame index or -1");
	r.ground_truth = gt != 0;
	r.first_fix_frame = static_cast<int>(firstFix);
	checkPairRecord(r, path);
	return r;
}

}  // namespace shadyloc::eval
