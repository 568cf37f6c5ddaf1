/* ShadyLoc tests: setup tests of ctest fixtures (tests/CMakeLists.txt runs
 * them before the tests that require them; see Sequences.h). */
#include "Sequences.h"

#include <gtest/gtest.h>

#include <filesystem>

TEST(TestFixtures, WriteCorridorSequences)
{
	const std::string dir = shadyloc::test::fixtureDir();
	if (dir.empty()) GTEST_SKIP() << "SHADYLOC_FIXTURE_DIR unset: outside ctest, tests render their own frames";
	shadyloc::test::writeCorridorFixtures(dir);
	// Read back through the loader the tests use.
	const auto& s = shadyloc::test::corridorSequence(50, 0.1);
	EXPECT_EQ(s.left.size(), 50u);
	EXPECT_EQ(s.left[0].type(), CV_8UC3);
}
