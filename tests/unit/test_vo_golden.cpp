/* The stereo VO's trajectories on the default dataset are bit-identical to the
 * committed hashes (tests/golden/vo_default_hashes.txt, made by
 * scripts/vo-golden-hashes.sh): a refactor of the VO must not change a bit,
 * and a change meant to alter results updates the file in the same commit.
 *
 * Slow (about 2 minutes on two cores the first time): the default dataset
 * with the committed hashes is read where it exists (rawlogs/generated, or
 * the ctest fixture default_data), else rendered once into the build tree
 * (build/tests/tmp/vo_golden/data) and reused while it exists. */
#include "../support/TestSupport.h"

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

using namespace shadyloc;
namespace fs = std::filesystem;

namespace
{
/** name -> sha256 from `sha256sum` lines ("HASH  NAME"); '#' lines are comments. */
std::map<std::string, std::string> readHashes(std::istream& in)
{
	std::map<std::string, std::string> h;
	std::string line;
	while (std::getline(in, line))
	{
		if (line.empty() || line[0] == '#') continue;
		std::istringstream ss(line);
		std::string hash, name;
		if (ss >> hash >> name) h[name] = hash;
	}
	return h;
}

std::string sha256(const std::string& file)
{
	std::string out;
	if (test::runCommand("sha256sum '" + file + "'", &out) != 0) return {};
	return out.substr(0, out.find(' '));
}
}  // namespace

TEST(VoGolden, DefaultDatasetTrajectoriesMatchCommittedHashes)
{
	const std::string src = SHADYLOC_SOURCE_DIR;
	std::ifstream f(src + "/tests/golden/vo_default_hashes.txt");
	ASSERT_TRUE(f.good()) << "tests/golden/vo_default_hashes.txt missing";
	const auto expected = readHashes(f);
	ASSERT_EQ(expected.size(), 12u) << "expected 4 rawlogs + 8 trajectories in vo_default_hashes.txt";

	const char* tmp = std::getenv("SHADYLOC_TMP");
	const fs::path work = fs::path(tmp ? tmp : fs::temp_directory_path().string()) / "vo_golden";
	fs::create_directories(work);

	// A dataset already on disk with the committed hashes (the checkout's
	// rawlogs/generated, or the ctest fixture's rendering) saves rendering it.
	std::string data;
	const std::string found = test::defaultDatasetDir();
	bool reuse = !found.empty();
	for (const auto& [name, hash] : expected)
		if (reuse && name.rfind("data/", 0) == 0 && sha256(found + "/" + name.substr(5)) != hash) reuse = false;
	if (reuse) data = found;

	const std::string hashes = (work / "hashes.txt").string(), log = (work / "log.txt").string();
	const std::string cmd = "SHADYLOC_APP='" + test::appPath() + "' bash '" + src +
							"/scripts/vo-golden-hashes.sh' '" + work.string() + "' " +
							(data.empty() ? "" : "'" + data + "' ") + "> '" + hashes + "' 2> '" + log + "'";
	std::string out;
	ASSERT_EQ(test::runCommand(cmd, &out), 0) << out << "\nsee " << log;
	std::ifstream g(hashes);
	const auto got = readHashes(g);

	for (const auto& [name, hash] : expected)
	{
		const auto it = got.find(name);
		ASSERT_NE(it, got.end()) << name << " not produced (see " << log << ")";
		if (name.rfind("data/", 0) == 0)
			// A different dataset voids the comparison: say so rather than blame the VO.
			ASSERT_EQ(it->second, hash) << name
										<< ": the default dataset differs from the committed one "
										   "(simulator or rawlog format changed); regenerate the hashes";
		else
			EXPECT_EQ(it->second, hash) << name << " differs from the committed trajectory (VO results changed; "
											   "output in " << (work / "vo").string() << ")";
	}
}
