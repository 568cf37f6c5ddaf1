/* ShadyLoc — the run list of a leave-one-out evaluation (docs/evaluation.md). */
#include <shadyloc/eval/RunList.h>

#include <filesystem>
#include <fstream>
#include <iomanip>
#include <map>
#include <sstream>
#include <cctype>
#include <stdexcept>

namespace shadyloc::eval
{
namespace fs = std::filesystem;

std::string runWhere(const std::string& listPath, const TRun& r)
{
	return listPath + ":" + std::to_string(r.line) + ": run '" + r.name + "'";
}

namespace
{
const char* const kQuoteHint = " (a path with spaces must be in double quotes: \"my runs/a.rawlog\")";

/** The same file, through any link or relative path. */
bool sameFile(const std::string& a, const std::string& b)
{
	std::error_code ec;
	return fs::equivalent(a, b, ec) && !ec;
}
}  // namespace

std::vector<TRun> readRunList(const std::string& path)
{
	if (!fs::exists(path)) throw std::runtime_error("run list '" + path + "' does not exist");
	if (fs::is_directory(path)) throw std::runtime_error("run list '" + path + "' is a directory, not a file");
	std::ifstream in(path);
	if (!in) throw std::runtime_error("run list '" + path + "': cannot read it");
	const fs::path base = fs::path(path).parent_path();
	const auto resolve = [&](const std::string& p) {
		const fs::path q(p);
		return (q.is_absolute() || base.empty() ? q : base / q).lexically_normal().string();
	};
	std::vector<TRun> runs;
	std::map<std::string, int> seen;
	std::string line;
	for (int n = 1; std::getline(in, line); n++)
	{
		const std::string at = path + ":" + std::to_string(n) + ": ";
		if (const auto h = line.find('#'); h != std::string::npos) line.erase(h);
		if (!line.empty() && line.back() == '\r') line.pop_back();
		// A path with spaces is written in double quotes ("my runs/a.rawlog").
		std::istringstream fields(line);
		std::vector<std::string> f;
		for (std::string w; fields >> std::quoted(w);) f.push_back(w);
		if (f.empty()) continue;
		if (f.size() < 2 || f.size() > 3)
			throw std::runtime_error(
				at + std::to_string(f.size()) + " field" + (f.size() == 1 ? "" : "s") +
				"; a run is 'name rawlog [ground_truth.tum]'" + (f.size() > 3 ? kQuoteHint : ""));
		TRun r;
		r.name = f[0];
		r.line = n;
		for (const char c : r.name)
			if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-'))
				throw std::runtime_error(
					at + "run name '" + r.name + "': only letters, digits, '_' and '-' (it names output folders)");
		if (const auto it = seen.find(r.name); it != seen.end())
			throw std::runtime_error(
				at + "run name '" + r.name + "' is already used on line " + std::to_string(it->second) +
				" (names must be unique)");
		seen[r.name] = n;
		r.rawlog = f[1];
		r.rawlogPath = resolve(f[1]);
		if (f.size() == 3)
		{
			r.gt = f[2];
			r.gtPath = resolve(f[2]);
		}
		if (!fs::is_regular_file(r.rawlogPath))
			throw std::runtime_error(
				at + "run '" + r.name + "': rawlog '" + r.rawlogPath + "' does not exist" +
				(fs::exists(r.rawlogPath) ? " as a file" : "") + (f.size() == 3 ? kQuoteHint : ""));
		if (r.hasGt() && !fs::is_regular_file(r.gtPath))
			throw std::runtime_error(at + "run '" + r.name + "': ground truth '" + r.gtPath + "' does not exist");
		// The same traversal twice would be localised against its own map.
		for (const auto& o : runs)
			if (sameFile(o.rawlogPath, r.rawlogPath))
				throw std::runtime_error(
					at + "run '" + r.name + "': rawlog '" + r.rawlogPath + "' is run '" + o.name + "''s (line " +
					std::to_string(o.line) + "): each run must be a traversal of its own");
		runs.push_back(std::move(r));
	}
	if (runs.size() < 2)
		throw std::runtime_error(
			"run list '" + path + "': " + std::to_string(runs.size()) +
			" run(s); leave-one-out needs at least 2 (each run against the map of every other)");
	return runs;
}

}  // namespace shadyloc::eval
