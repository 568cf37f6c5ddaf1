/* Bad-input weaknesses: interrupted commands leave no temporaries (and name
 * stale ones from killed runs), clear messages naming the file or option,
 * nothing accepted silently, and a damaged rawlog read with bounded memory. */
#include "../support/TestSupport.h"

#include <shadyloc/io/OutputTransaction.h>
#include <shadyloc/io/Rawlog.h>

#include <mrpt/io/CMemoryStream.h>
#include <mrpt/serialization/CArchive.h>

#include <zlib.h>

#include <chrono>
#include <csignal>
#include <fstream>
#include <regex>
#include <sstream>
#include <thread>

#include <fcntl.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

using namespace shadyloc;
namespace fs = std::filesystem;

namespace
{
/** Hidden temporaries (ours: ".<name>.tmp-<pid>...") anywhere under dir. */
std::vector<std::string> temporariesUnder(const std::string& dir)
{
	std::vector<std::string> out;
	for (const auto& e : fs::recursive_directory_iterator(dir))
		if (e.path().filename().string().find(".tmp") != std::string::npos) out.push_back(e.path().string());
	return out;
}


/** A copy of config/sim.ini with `frames` frames per traversal. */
std::string smallSimConfig(const std::string& dir, int frames)
{
	std::ifstream in(std::string(SHADYLOC_SOURCE_DIR) + "/config/sim.ini");
	std::stringstream s;
	s << in.rdbuf();
	const std::string path = dir + "/sim.ini";
	std::ofstream(path) << std::regex_replace(s.str(), std::regex("(frames|end_s_m) = [0-9]+"), "frames = " + std::to_string(frames));
	return path;
}

}  // namespace

TEST(Interrupts, SigintAndSigtermRemoveTemporaries)
{
	for (int sig : {SIGINT, SIGTERM})
	{
		const auto dir = test::tempDir("interrupt_" + std::to_string(sig));
		const std::string cfg = smallSimConfig(dir, 400);
		const pid_t pid = test::spawnApp({"sim", "-c", cfg, "-o", dir + "/out"}, dir + "/log.txt");
		// Wait until the first rawlog is being written, then interrupt.
		bool started = false;
		for (int i = 0; i < 600 && !started; i++)
		{
			std::this_thread::sleep_for(std::chrono::milliseconds(50));
			started = fs::is_directory(dir + "/out") && !temporariesUnder(dir + "/out").empty();
		}
		ASSERT_TRUE(started) << test::fileContents(dir + "/log.txt");
		kill(pid, sig);
		int status = 0;
		waitpid(pid, &status, 0);
		EXPECT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == sig) << "status " << status;
		EXPECT_TRUE(temporariesUnder(dir).empty()) << "left: " << temporariesUnder(dir)[0];
		EXPECT_FALSE(fs::exists(dir + "/out/noon.rawlog"));
		EXPECT_NE(test::fileContents(dir + "/log.txt").find("temporary output(s) removed"), std::string::npos);
	}
}

TEST(Interrupts, StaleTemporariesOfKilledRunsAreNamed)
{
	const auto dir = test::tempDir("stale_tmp");
	test::writeSyntheticRawlog(dir + "/in.rawlog", 2, false);
	// What a SIGKILLed run leaves: a temporary whose process is gone.
	const std::string stale = dir + "/.out.tmp-999999999.rawlog";
	std::ofstream(stale) << "half";
	fs::create_directory(dir + "/.out_Images.tmp-999999999");
	std::string out;
	ASSERT_EQ(test::runCommand(test::appPath() + " filter -q -i " + dir + "/in.rawlog -o " + dir + "/out.rawlog", &out), 0)
		<< out;
	EXPECT_NE(out.find(stale), std::string::npos) << out;
	EXPECT_NE(out.find("rm -rf -- '" + stale + "'"), std::string::npos) << out;
	EXPECT_NE(out.find(".out_Images.tmp-999999999"), std::string::npos) << out;
	EXPECT_TRUE(fs::exists(stale)) << "a stale temporary is named, not deleted behind the user's back";
	const auto left = io::staleTemporaries(dir);
	EXPECT_EQ(left.size(), 2u);
}

TEST(Messages, NameTheFileOrOption)
{
	const auto dir = test::tempDir("messages");
	test::writeSyntheticRawlog(dir + "/r.rawlog", 2, false);
	std::ofstream(dir + "/empty.tum") << "# nothing\n";
	std::ofstream(dir + "/t.tum") << "1 0 0 0 0 0 0 1\n2 1 0 0 0 0 0 1\n3 2 0 0 0 0 0 1\n";
	struct Case
	{
		std::string args, expect;
	};
	const std::vector<Case> cases{
		{"traj-error --gt " + dir + "/empty.tum --est " + dir + "/t.tum", dir + "/empty.tum"},
		{"traj-error --gt " + dir + " --est " + dir + "/t.tum", "is a directory"},
		{"render -t " + dir + "/t.tum -o " + dir + "/o.png --width 0", "--width"},
		{"render -t " + dir + "/t.tum -o " + dir + "/o.xyz", "unknown image format '.xyz'"},
		{"export kitti -i " + dir + "/r.rawlog -o ''", "--output: empty value"},
		{"vo -i " + dir + "/r.rawlog -o ''", "--output: empty value"},
		{"image " + dir + "/a.png ''", "empty value"},
		{"image " + dir + "/t.tum " + dir + "/o.png --wavelengths 470,540,620,700", "three values"},
		{"image " + dir + "/t.tum " + dir + "/o.png --wavelengths 470,540,620 --alpha 0.4", "--wavelengths"},
		{"image " + dir + "/t.tum " + dir + "/o.png", "not an image file"},
		{"image " + dir + "/t.tum " + dir + "/o.png --gamma 2", "--linearise gamma"},
		{"filter -i " + dir + "/r.rawlog -o " + dir + "/f.rawlog -c " + dir + "/labels.ini", "NOSUCHCAM"}};
	std::ofstream(dir + "/labels.ini") << "[filters]\npipeline = m\n[m]\nclass = CFilterMonochrome\nsensor_labels = NOSUCHCAM\n";
	for (const auto& c : cases)
	{
		std::string out;
		EXPECT_NE(test::runCommand(test::appPath() + " " + c.args, &out), 0) << c.args << "\n" << out;
		EXPECT_NE(out.find(c.expect), std::string::npos) << c.args << ": lacks '" << c.expect << "'\n" << out;
		EXPECT_EQ(out.find("Call stack"), std::string::npos) << c.args << ": a call-stack dump\n" << out;
	}
	EXPECT_FALSE(fs::exists(dir + "/f.rawlog"));
	EXPECT_TRUE(temporariesUnder(dir).empty());
}

TEST(Messages, ImportFolderRefusesTimesThatDoNotIncrease)
{
	const auto dir = test::tempDir("times_order");
	fs::create_directories(dir + "/L");
	fs::create_directories(dir + "/R");
	for (int i = 0; i < 3; i++)
	{
		auto obs = test::syntheticStereoFrame(i, 32, 24);
		ASSERT_TRUE(obs->imageLeft.saveToFile(dir + "/L/" + std::to_string(i) + ".png"));
		ASSERT_TRUE(obs->imageRight.saveToFile(dir + "/R/" + std::to_string(i) + ".png"));
	}
	std::ofstream(dir + "/calib.ini") << "[left]\nfx_px = 50\nfy_px = 50\ncx_px = 16\ncy_px = 12\n[stereo]\nbaseline_m = 0.1\nwidth_px = 32\nheight_px = 24\n";
	const std::string base = test::appPath() + " import folder -q --left " + dir + "/L --right " + dir + "/R --calib " +
		dir + "/calib.ini -o " + dir + "/out.rawlog --times ";
	for (const char* times : {"1.0\n3.0\n2.0\n", "1.0\n1.0\n2.0\n", "1.0\nnan\n2.0\n"})
	{
		std::ofstream(dir + "/times.txt") << times;
		std::string out;
		EXPECT_NE(test::runCommand(base + dir + "/times.txt", &out), 0) << times << out;
		EXPECT_NE(out.find(dir + "/times.txt"), std::string::npos) << out;
		EXPECT_FALSE(fs::exists(dir + "/out.rawlog"));
	}
	std::ofstream(dir + "/times.txt") << "1.0\n2.0\n3.0\n";
	std::string out;
	EXPECT_EQ(test::runCommand(base + dir + "/times.txt", &out), 0) << out;
}

// A run name is written unquoted into localise's frames.csv (kf_run): a comma
// split its rows. survey refuses such a name, saying which characters a name
// may hold, and writes no map.
TEST(Messages, SurveyRefusesRunNamesFramesCsvCannotHold)
{
	const auto dir = test::tempDir("run_name");
	test::writeSyntheticRawlog(dir + "/r.rawlog", 3, false);
	test::writeSyntheticRawlog(dir + "/a,b.rawlog", 3, false);
	for (const std::string& args : {"-i " + dir + "/r.rawlog --run-name a,b", "-i '" + dir + "/a,b.rawlog'",
									"-i " + dir + "/r.rawlog --run-name 'a\"b'"})
	{
		std::string out;
		EXPECT_NE(test::runCommand(test::appPath() + " survey -q " + args + " -o " + dir + "/m.kfmap", &out), 0)
			<< args << "\n" << out;
		EXPECT_NE(out.find("only letters, digits"), std::string::npos) << args << "\n" << out;
		EXPECT_FALSE(fs::exists(dir + "/m.kfmap")) << args;
	}
}

TEST(OutputsTogether, TransactionCommitsAllOrNothing)
{
	const auto dir = test::tempDir("tx_all_or_nothing");
	std::ofstream(dir + "/a.txt") << "old a";
	std::ofstream(dir + "/b.txt") << "old b";
	{
		io::OutputTransaction tx;
		std::ofstream(tx.addFile(dir + "/a.txt")) << "new a";
		const std::string b = tx.addFile(dir + "/b.txt");
		(void)b;  // never written: commit must fail and change nothing
		EXPECT_THROW(tx.commit(), std::runtime_error);
	}
	EXPECT_EQ(test::fileContents(dir + "/a.txt"), "old a");
	EXPECT_EQ(test::fileContents(dir + "/b.txt"), "old b");
	EXPECT_TRUE(temporariesUnder(dir).empty());
	{
		io::OutputTransaction tx;
		std::ofstream(tx.addFile(dir + "/a.txt")) << "new a";
		const std::string d = tx.addDirectory(dir + "/d", "output", "test output");
		std::ofstream(d + "/x") << "x";
		tx.commit();
	}
	EXPECT_EQ(test::fileContents(dir + "/a.txt"), "new a");
	EXPECT_EQ(test::fileContents(dir + "/d/x"), "x");
	EXPECT_TRUE(temporariesUnder(dir).empty());
	// Inputs: by path, through a symbolic link, a hard link, and a folder
	// replaced as a whole that holds one.
	fs::create_symlink(dir + "/a.txt", dir + "/sym.txt");
	fs::create_hard_link(dir + "/a.txt", dir + "/hard.txt");
	io::OutputTransaction tx;
	tx.addInput(dir + "/a.txt", "input");
	tx.addInput(dir + "/d/x", "input in d");
	EXPECT_THROW(tx.addFile(dir + "/a.txt"), std::invalid_argument);
	EXPECT_THROW(tx.addFile(dir + "/sym.txt"), std::invalid_argument);
	EXPECT_THROW(tx.addFile(dir + "/hard.txt"), std::invalid_argument);
	EXPECT_THROW(tx.addDirectory(dir + "/d", "output", "test output"), std::invalid_argument);
	EXPECT_THROW(tx.addFile(""), std::invalid_argument);
	EXPECT_THROW(tx.addFile(dir + "/missing/x.txt"), std::invalid_argument);
	const std::string ok = tx.addFile(dir + "/c.txt");
	EXPECT_THROW(tx.addFile(dir + "/./c.txt"), std::invalid_argument);
}

// A folder output replaces an existing folder only if it is empty or marked
// as an earlier output of the same kind: a folder of the user's files is
// refused by name and left as it was.
TEST(OutputsTogether, FolderReplacedOnlyIfAnEarlierOutputOfTheSameKind)
{
	const auto dir = test::tempDir("tx_folder_kind");
	fs::create_directories(dir + "/user");
	std::ofstream(dir + "/user/thesis.tex") << "years of work";
	{
		io::OutputTransaction tx;
		try
		{
			tx.addDirectory(dir + "/user", "output folder", "test output");
			ADD_FAILURE() << "a folder of the user's files was accepted";
		}
		catch (const std::invalid_argument& e)
		{
			EXPECT_NE(std::string(e.what()).find("'" + dir + "/user'"), std::string::npos) << e.what();
		}
	}
	EXPECT_EQ(test::fileContents(dir + "/user/thesis.tex"), "years of work");
	EXPECT_TRUE(temporariesUnder(dir).empty());

	// Empty: replaced; then marked, so the next run of that kind replaces it
	// (a trailing '/' names the same folder).
	fs::create_directories(dir + "/out");
	for (const std::string content : {"1", "2"})
	{
		io::OutputTransaction tx;
		const std::string to = dir + (content == "1" ? "/out" : "/out/");
		std::ofstream(tx.addDirectory(to, "output folder", "test output") + "/x") << content;
		tx.commit();
		EXPECT_EQ(test::fileContents(dir + "/out/x"), content);
	}
	EXPECT_EQ(test::fileContents(dir + "/out/" + io::kOutputMarker), "test output\n");
	// Another kind's output is refused.
	io::OutputTransaction tx;
	EXPECT_THROW(tx.addDirectory(dir + "/out", "output folder", "other output"), std::invalid_argument);
	EXPECT_EQ(test::fileContents(dir + "/out/x"), "2");
}

namespace
{
using test::Bytes;
Bytes gzipBytes(const Bytes& b)
{
	uLongf n = compressBound(static_cast<uLong>(b.size())) + 64;
	Bytes out(n);
	z_stream z{};
	deflateInit2(&z, 1, Z_DEFLATED, 15 + 16, 8, Z_DEFAULT_STRATEGY);
	z.next_in = const_cast<Bytef*>(b.data());
	z.avail_in = static_cast<uInt>(b.size());
	z.next_out = out.data();
	z.avail_out = static_cast<uInt>(out.size());
	deflate(&z, Z_FINISH);
	out.resize(out.size() - z.avail_out);
	deflateEnd(&z);
	return out;
}
/** Peak resident memory [kB] of `shadyloc args` (ru_maxrss of the child). */
long peakKb(const std::vector<std::string>& args, const std::string& log, int* exitCode)
{
	const pid_t pid = test::spawnApp(args, log);
	int status = 0;
	struct rusage ru
	{
	};
	wait4(pid, &status, 0, &ru);
	*exitCode = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
	return ru.ru_maxrss;
}
}  // namespace

TEST(DamagedRawlog, EveryHeaderByteFlippedIsAnErrorOrReadsAndMemoryStaysBounded)
{
	const auto dir = test::tempDir("damaged_rawlog");
	mrpt::io::CMemoryStream mem;
	auto arch = mrpt::serialization::archiveFrom(mem);
	for (int i = 0; i < 2; i++) arch << *test::syntheticStereoFrame(i, 320, 240);
	const auto* p = static_cast<const uint8_t*>(mem.getRawBufferData());
	const Bytes valid(p, p + mem.getPosition());
	test::writeBytes(dir + "/valid.rawlog", gzipBytes(valid));

	// Every byte of the first object's header (class names, poses, camera
	// models, image sizes), flipped: an error naming the file, or a read.
	std::vector<size_t> lengthFaults;
	const std::string damaged = dir + "/damaged.rawlog";
	for (size_t i = 0; i < 600; i++)
	{
		Bytes b = valid;
		b[i] ^= 0xFF;
		test::writeBytes(damaged, gzipBytes(b));
		try
		{
			io::RawlogReader r(damaged);
			while (r.next())
			{
			}
		}
		catch (const io::RawlogError& e)
		{
			const std::string w = e.what();
			EXPECT_NE(w.find(damaged), std::string::npos) << "byte " << i << ": " << w;
			if (w.find("more than remain") != std::string::npos) lengthFaults.push_back(i);
		}
		catch (const std::exception& e)
		{
			ADD_FAILURE() << "byte " << i << ": not a RawlogError: " << e.what();
		}
	}
	// Some flips hit length fields (a string's, an image's size) that would
	// have asked for up to 4 GB.
	ASSERT_FALSE(lengthFaults.empty());

	// Peak memory of a whole command on those, against a valid rawlog:
	// within valid + 2 x the decompressed size + 64 MB.
	int rc = 0;
	const long validKb = peakKb({"filter", "-q", "-i", dir + "/valid.rawlog", "-o", dir + "/out.rawlog"}, dir + "/log", &rc);
	ASSERT_EQ(rc, 0) << test::fileContents(dir + "/log");
	const long boundKb = validKb + long(2 * valid.size() / 1024) + 64 * 1024;
	for (size_t k = 0; k < lengthFaults.size() && k < 4; k++)
	{
		Bytes b = valid;
		b[lengthFaults[k]] ^= 0xFF;
		test::writeBytes(damaged, gzipBytes(b));
		const long kb = peakKb({"filter", "-q", "-i", damaged, "-o", dir + "/out2.rawlog"}, dir + "/log", &rc);
		EXPECT_NE(rc, 0);
		EXPECT_LE(kb, boundKb) << "byte " << lengthFaults[k] << ": peak " << kb << " kB, valid " << validKb << " kB";
	}
}
