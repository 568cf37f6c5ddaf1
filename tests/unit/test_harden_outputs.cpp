/* A command's outputs are committed together or not at all, and no output
 * may be one of its inputs (also through a symbolic or hard link). */
#include "../support/TestSupport.h"

#include <fstream>
#include <sstream>

using namespace shadyloc;
namespace fs = std::filesystem;

namespace
{
}  // namespace

TEST(OutputsNotInputs, VoRefusesToWriteOverItsInput)
{
	const auto dir = test::tempDir("vo_out_is_in");
	const std::string in = dir + "/r.rawlog";
	test::writeSyntheticRawlog(in, 4, false);
	const std::string original = test::fileContents(in);
	fs::create_symlink(in, dir + "/link.rawlog");
	fs::create_hard_link(in, dir + "/hard.rawlog");
	const std::string vo = test::appPath() + " vo -q -i " + in;
	for (const std::string& args :
		 {" -o " + in, " -o " + dir + "/link.rawlog", " -o " + dir + "/hard.rawlog", " -o " + dir + "/./r.rawlog",
		  " -o " + dir + "/t.tum --stats " + in, " -o " + dir + "/t.tum --keyframes " + dir + "/link.rawlog",
		  " -o " + dir + "/t.tum --stats " + dir + "/t.tum"})
	{
		std::string out;
		EXPECT_NE(test::runCommand(vo + args, &out), 0) << args << ": " << out;
		EXPECT_EQ(test::fileContents(in), original) << args << ": the input rawlog was replaced";
		EXPECT_FALSE(fs::exists(dir + "/t.tum")) << args;
	}
}

TEST(OutputsTogether, VoWritesNoTrajectoryWhenStatsCannotBeWritten)
{
	const auto dir = test::tempDir("vo_out_together");
	const std::string in = dir + "/r.rawlog";
	test::writeSyntheticRawlog(in, 4, false);
	for (const std::string& bad : {" --stats " + dir + "/missing/s.csv", " --keyframes " + dir + "/missing/k.csv"})
	{
		fs::remove(dir + "/t.tum");
		std::string out;
		EXPECT_NE(test::runCommand(test::appPath() + " vo -q -i " + in + " -o " + dir + "/t.tum" + bad, &out), 0) << out;
		EXPECT_FALSE(fs::exists(dir + "/t.tum")) << bad << ": trajectory committed although the command failed";
		// An earlier trajectory stays as it was.
		{
			std::ofstream f(dir + "/t.tum");
			f << "# old\n";
		}
		EXPECT_NE(test::runCommand(test::appPath() + " vo -q -i " + in + " -o " + dir + "/t.tum" + bad, &out), 0) << out;
		EXPECT_EQ(test::fileContents(dir + "/t.tum"), "# old\n") << bad;
	}
}
