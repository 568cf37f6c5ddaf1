/* Kill tests of every command with a folder output (issue #23, must-show 2):
 * `filter` and `import` (a rawlog's images folder), `export kitti` (the
 * sequence folder), `localise -o` (and its `--learn` map) and `eval` (job
 * folders, pairs/, figures/).
 *
 * Each command runs once to completion; a file is then added to each of its
 * folders, so that the previous output can be told from a new one. The
 * command runs again and is sent SIGINT, then SIGTERM, as soon as its
 * temporary appears: afterwards every folder is the previous output whole or
 * the new one complete, and nothing of the interrupted run is left. Last it
 * is sent SIGKILL, which cannot be caught: the previous output is still
 * whole, the temporary is still there, and a rerun completes, names the stale
 * temporary with the command that deletes it, and does not delete it. */
#include "../support/TestSupport.h"

#include <chrono>
#include <csignal>
#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <thread>

#include <fcntl.h>
#include <sys/wait.h>
#include <unistd.h>

using namespace shadyloc;
namespace fs = std::filesystem;

namespace
{
/** Every regular file under a path (relative name -> bytes); a file: {".": bytes} (test::snapshot). */
using Snapshot = std::map<std::string, std::string>;

/** The same files; the same bytes except in files named in `varying` (timings). */
bool sameOutput(const Snapshot& a, const Snapshot& b, const std::set<std::string>& varying)
{
	if (a.size() != b.size()) return false;
	for (auto i = a.begin(), j = b.begin(); i != a.end(); ++i, ++j)
		if (i->first != j->first || (i->second != j->second && !varying.count(fs::path(i->first).filename().string())))
			return false;
	return true;
}

std::string describe(const Snapshot& s)
{
	std::string d;
	for (const auto& [name, bytes] : s) d += "  " + name + " (" + std::to_string(bytes.size()) + " bytes)\n";
	return d.empty() ? "  (nothing)\n" : d;
}


/** Staged entries (".<name>.tmp-<pid>..." or ".old-<pid>") of process `pid` in `dirs`. */
std::vector<std::string> stagedOf(pid_t pid, const std::set<std::string>& dirs, const std::string& namePrefix = "")
{
	const std::regex re(R"(^\..*\.(tmp|old)-)" + std::to_string(pid) + R"((\..*)?$)");
	std::vector<std::string> out;
	for (const auto& d : dirs)
	{
		std::error_code ec;
		for (fs::directory_iterator it(d, ec), end; !ec && it != end; it.increment(ec))
		{
			const std::string name = it->path().filename().string();
			if (std::regex_match(name, re) && name.rfind(namePrefix, 0) == 0) out.push_back(it->path().string());
		}
	}
	return out;
}

struct TKillCase
{
	std::vector<std::string> args;	  //!< the command (after `shadyloc`)
	std::vector<std::string> outputs;  //!< its folder outputs (and files written with them)
	std::set<std::string> varying;	  //!< file names whose bytes differ between runs
	/** Where each signal is sent: when a temporary whose name starts so
	 * appears (SIGINT, SIGTERM, SIGKILL); "" = any temporary of the run. */
	std::vector<std::string> killAt{"", "", ""};
};

class Killer
{
   public:
	Killer(const TKillCase& c, const std::string& logDir) : m_c(c), m_log(logDir + "/kill_log.txt")
	{
		for (const auto& o : c.outputs) m_dirs.insert(fs::path(o).parent_path().string());
	}

	/** The first, complete run; marks each folder so that it can be told from a new output. */
	void firstRun()
	{
		runToEnd("first run");
		for (const auto& o : m_c.outputs)
		{
			if (fs::is_directory(o)) std::ofstream(o + "/previous.txt") << "from the previous run\n";
			m_old[o] = test::snapshot(o);
			m_new[o] = m_old[o];
			m_new[o].erase("previous.txt");
		}
	}

	/** Interrupts a run with `sig` (SIGINT or SIGTERM) once its temporary appears. */
	void interrupt(int sig, const std::string& at)
	{
		SCOPED_TRACE("signal " + std::to_string(sig));
		const pid_t pid = test::spawnApp(m_c.args, m_log);
		ASSERT_TRUE(waitForTemporary(pid, at)) << test::fileContents(m_log);
		kill(pid, sig);
		int status = 0;
		waitpid(pid, &status, 0);
		// Ended by the signal, or (a signal arriving during the commit waits
		// for it) finished just before.
		EXPECT_TRUE((WIFSIGNALED(status) && WTERMSIG(status) == sig) || (WIFEXITED(status) && WEXITSTATUS(status) == 0))
			<< "status " << status << "\n" << test::fileContents(m_log);
		const auto left = stagedOf(pid, m_dirs);
		EXPECT_TRUE(left.empty()) << "left behind: " << left.front();
		expectOldOrNew();
		remark();
	}

	/** SIGKILL once the temporary appears, then a rerun that names what was left. */
	void killAndRerun(const std::string& at)
	{
		const pid_t pid = test::spawnApp(m_c.args, m_log);
		ASSERT_TRUE(waitForTemporary(pid, at)) << test::fileContents(m_log);
		kill(pid, SIGKILL);
		int status = 0;
		waitpid(pid, &status, 0);
		ASSERT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL) << "status " << status;
		expectOldOrNew();
		const auto stale = stagedOf(pid, m_dirs);
		ASSERT_FALSE(stale.empty()) << "SIGKILL cannot remove a temporary: one should be left";

		const std::string out = runToEnd("rerun after SIGKILL");
		for (const auto& s : stale)
		{
			EXPECT_NE(out.find("'" + s + "': temporary output left by an interrupted run"), std::string::npos) << s << "\n"
																											  << out;
			EXPECT_NE(out.find("rm -rf -- '" + s + "'"), std::string::npos) << out;
			EXPECT_TRUE(fs::exists(s)) << s << ": a stale temporary is named, not deleted behind the user's back";
		}
		for (const auto& o : m_c.outputs)
			EXPECT_TRUE(sameOutput(test::snapshot(o), m_new[o], m_c.varying))
				<< o << ": the rerun's output is not complete:\n" << describe(test::snapshot(o)) << "expected\n" << describe(m_new[o]);
		for (const auto& s : stale) fs::remove_all(s);
	}

	void runAll()
	{
		firstRun();
		if (::testing::Test::HasFatalFailure()) return;
		interrupt(SIGINT, m_c.killAt[0]);
		interrupt(SIGTERM, m_c.killAt[1]);
		killAndRerun(m_c.killAt[2]);
	}

   private:
	std::string runToEnd(const std::string& what)
	{
		const pid_t pid = test::spawnApp(m_c.args, m_log);
		int status = 0;
		waitpid(pid, &status, 0);
		const std::string out = test::fileContents(m_log);
		EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << what << ": status " << status << "\n" << out;
		return out;
	}

	/** True once a temporary of `pid` whose name starts with `prefix` exists
	 * (polled every millisecond); false if the run ended first. */
	bool waitForTemporary(pid_t pid, const std::string& prefix)
	{
		for (int i = 0; i < 300000; i++)
		{
			if (!stagedOf(pid, m_dirs, prefix).empty()) return true;
			int status = 0;
			if (waitpid(pid, &status, WNOHANG) == pid)
			{
				ADD_FAILURE() << "the run ended (status " << status << ") before a temporary '" << prefix << "...' appeared";
				return false;
			}
			std::this_thread::sleep_for(std::chrono::milliseconds(1));
		}
		kill(pid, SIGKILL);
		waitpid(pid, nullptr, 0);
		return false;
	}

	/** Each output is the previous one whole or the new one complete, nothing in between. */
	void expectOldOrNew()
	{
		for (const auto& o : m_c.outputs)
		{
			const auto now = test::snapshot(o);
			EXPECT_TRUE(now == m_old[o] || sameOutput(now, m_new[o], m_c.varying))
				<< o << " is neither the previous output nor a complete new one:\n"
				<< describe(now) << "previous:\n" << describe(m_old[o]);
		}
	}

	/** Marks a folder that a completed run replaced again, so the next check tells old from new. */
	void remark()
	{
		for (const auto& o : m_c.outputs)
			if (fs::is_directory(o) && !fs::exists(o + "/previous.txt"))
			{
				std::ofstream(o + "/previous.txt") << "from the previous run\n";
				m_old[o] = test::snapshot(o);
			}
	}

	TKillCase m_c;
	std::string m_log;
	std::set<std::string> m_dirs;  //!< where the temporaries appear
	std::map<std::string, Snapshot> m_old, m_new;
};

/** Two short traversals of config/sim.ini (8 frames, 512x384) in dir/sim. */
std::string simRuns(const std::string& dir, const std::string& traversals)
{
	std::string out;
	const int rc = test::runCommand(
		test::appPath() + " sim -q -c " + test::sourcePath("config/sim.ini") + " -o " + dir + "/sim --traversals " + traversals +
			" --frames 8",
		&out);
	if (rc != 0) throw std::runtime_error("sim failed: " + out);
	return dir + "/sim";
}

/** The map of simRuns' noon traversal, surveyed into dir/noon.kfmap. */
std::string surveyedNoon(const std::string& dir, const std::string& sim)
{
	const std::string map = dir + "/noon.kfmap";
	std::string out;
	const int rc = test::runCommand(
		test::appPath() + " survey -q -i " + sim + "/noon.rawlog -o " + map + " -c " + test::sourcePath("config/vo_sim.ini") +
			" --gt " + sim + "/noon.tum",
		&out);
	if (rc != 0) throw std::runtime_error("survey failed: " + out);
	return map;
}
}  // namespace

TEST(KillFolderOutputs, FilterImagesFolder)
{
	const auto dir = test::tempDir("kill_filter");
	const std::string sim = simRuns(dir, "noon");
	TKillCase c;
	c.args = {"filter", "-q", "-i", sim + "/noon.rawlog", "-o", dir + "/out.rawlog", "--external-images"};
	c.outputs = {dir + "/out_Images", dir + "/out.rawlog"};
	Killer(c, dir).runAll();
}

TEST(KillFolderOutputs, ExportKittiSequenceAndImportImagesFolder)
{
	const auto dir = test::tempDir("kill_kitti");
	const std::string sim = simRuns(dir, "noon");
	TKillCase e;
	e.args = {"export", "kitti", "-q", "-i", sim + "/noon.rawlog", "-o", dir + "/kitti", "--gt", sim + "/noon.tum"};
	e.outputs = {dir + "/kitti/sequences/00", dir + "/kitti/poses/00.txt"};
	{
		SCOPED_TRACE("export kitti");
		Killer(e, dir).runAll();
	}
	TKillCase i;
	i.args = {"import", "kitti", "-q", dir + "/kitti", "-o", dir + "/imported.rawlog", "--external-images"};
	i.outputs = {dir + "/imported_Images", dir + "/imported.rawlog", dir + "/imported_gt.tum"};
	{
		SCOPED_TRACE("import kitti");
		Killer(i, dir).runAll();
	}
}

TEST(KillFolderOutputsSlow, LocaliseOutputFolder)
{
	const auto dir = test::tempDir("kill_localise");
	const std::string sim = simRuns(dir, "noon,overcast");
	const std::string map = surveyedNoon(dir, sim);
	TKillCase c;
	c.args = {"localise", "-q", "-m", map, "-i", sim + "/overcast.rawlog", "-o", dir + "/loc",
			  "-c", test::sourcePath("config/vo_sim.ini"), "-c", test::sourcePath("config/localise_sim.ini"), "--gt", sim + "/overcast.tum"};
	c.outputs = {dir + "/loc"};
	c.varying = {"timing.json"};
	Killer(c, dir).runAll();
}

// `localise --learn`: the learnt map is written with the folder, both or
// neither, and the map it learns from is never touched.
TEST(KillFolderOutputsSlow, LocaliseLearntMap)
{
	const auto dir = test::tempDir("kill_learn");
	const std::string sim = simRuns(dir, "noon,overcast");
	const std::string map = surveyedNoon(dir, sim);
	const std::string before = test::fileContents(map);
	TKillCase c;
	c.args = {"localise", "-q", "-m", map, "-i", sim + "/overcast.rawlog", "-o", dir + "/loc",
			  "-c", test::sourcePath("config/vo_sim.ini"), "-c", test::sourcePath("config/localise_sim.ini"), "--learn", dir + "/learnt.kfmap"};
	c.outputs = {dir + "/loc", dir + "/learnt.kfmap"};
	c.varying = {"timing.json"};
	Killer(c, dir).runAll();
	EXPECT_EQ(test::fileContents(map), before) << "the map learnt from, byte for byte";
}

TEST(KillFolderOutputsSlow, EvalJobFoldersPairsAndFigures)
{
	const auto dir = test::tempDir("kill_eval");
	const std::string sim = simRuns(dir, "noon,overcast");
	std::ofstream(sim + "/runs.txt") << "noon noon.rawlog noon.tum\novercast overcast.rawlog overcast.tum\n";
	const std::string o = dir + "/eval";
	TKillCase c;
	c.args = {"eval", "-q", "--runs", sim + "/runs.txt", "-o", o, "-c", test::sourcePath("config/vo_sim.ini"),
			  "-c", test::sourcePath("config/localise_sim.ini"), "-j", "1"};
	for (const char* job : {"map_noon", "map_overcast", "pair_noon__overcast__baseline", "pair_noon__overcast__combined",
							"pair_overcast__noon__baseline", "pair_overcast__noon__combined"})
		c.outputs.push_back(o + "/jobs/" + job);
	c.outputs.push_back(o + "/pairs");
	c.outputs.push_back(o + "/figures");
	c.varying = {"timing.json", "job_timing.json"};
	// SIGINT in a map job, SIGTERM in a pair job, SIGKILL during the merge.
	c.killAt = {".map_overcast.tmp-", ".pair_overcast__noon__baseline.tmp-", ".figures.tmp-"};
	Killer(c, dir).runAll();
}
