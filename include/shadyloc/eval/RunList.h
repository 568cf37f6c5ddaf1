/* ShadyLoc — the run list of a leave-one-out evaluation (docs/evaluation.md):
 * a small text file, one run a line,
 *
 *     # name    rawlog                   ground truth (optional)
 *     noon      generated/noon.rawlog    generated/noon.tum
 *     overcast  generated/overcast.rawlog
 *
 * fields separated by blanks (spaces or tabs), `#` starts a comment (whole
 * line or after the fields), blank lines ignored. Relative paths are relative
 * to the run list's folder. Names are unique, [A-Za-z0-9_-]+ (they name
 * output folders and the map's survey run).
 */
#pragma once

#include <string>
#include <vector>

namespace shadyloc::eval
{
struct TRun
{
	std::string name;
	std::string rawlog, gt;	 //!< as written in the list (gt "" if none)
	std::string rawlogPath, gtPath;	 //!< resolved against the list's folder
	int line = 0;  //!< 1-based line in the list
	bool hasGt() const { return !gt.empty(); }
};

/** Reads and checks a run list: syntax, names, that every file exists.
 * Throws std::runtime_error naming the file and line ("runs.txt:3: ..."). */
std::vector<TRun> readRunList(const std::string& path);

/** "<list>:<line>: run '<name>'", the prefix of errors about a run. */
std::string runWhere(const std::string& listPath, const TRun& r);

}  // namespace shadyloc::eval
