/* ShadyLoc tests: TUM trajectory files. */
#include <shadyloc/io/AtomicFile.h>
#include <shadyloc/io/Tum.h>

#include <Eigen/Dense>

#include "../support/TestSupport.h"

#include <cmath>
#include <fstream>
#include <random>

using namespace shadyloc::io;
namespace fs = std::filesystem;

namespace
{
mrpt::poses::CPose3D randomPose(std::mt19937& rng)
{
	std::uniform_real_distribution<double> t(-50, 50), a(-M_PI, M_PI), p(-1.5, 1.5);
	return mrpt::poses::CPose3D(t(rng), t(rng), t(rng), a(rng), p(rng), a(rng));
}

/** Largest |R_a - R_b| element: rotation difference, dimensionless. */
double rotDiff(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b)
{
	return (a.linear() - b.linear()).cwiseAbs().maxCoeff();
}
}  // namespace

TEST(IoTum, RoundTripToPrintPrecision)
{
	const std::string dir = shadyloc::test::tempDir("tum_roundtrip");
	std::mt19937 rng(7);
	Trajectory traj;
	for (int i = 0; i < 200; i++)
		traj.push_back({(i % 2 ? 1.6e9 : 0.0) + 0.1 * i + 1e-5 * i, toIsometry(randomPose(rng))});
	// Include a pose at pitch = 90 deg, where yaw/pitch/roll is singular.
	traj.push_back({5.0, toIsometry(mrpt::poses::CPose3D(1, 2, 3, 0.3, M_PI / 2, -0.2))});
	const std::string path = dir + "/traj.tum";
	writeTum(path, traj, "test trajectory");
	ASSERT_TRUE(fs::exists(path));
	EXPECT_FALSE(fs::exists(shadyloc::io::temporarySibling(path)));

	const auto back = readTum(path);
	ASSERT_EQ(back.size(), traj.size());
	for (size_t i = 0; i < traj.size(); i++)
	{
		// Times: printed with 9 decimals -> |error| <= 5e-10 s for small t; for
		// t ~ 1.6e9 the double's own spacing (2.4e-7) exceeds 1e-9, so the 9
		// decimals identify it exactly. 1e-9 is twice the print rounding.
		EXPECT_NEAR(back[i].t, traj[i].t, 1e-9) << "pose " << i;
		// Translation: 9 decimals -> 5e-10 m rounding; 1e-9 allows twice that.
		for (int k = 0; k < 3; k++)
			EXPECT_NEAR(back[i].T.translation()[k], traj[i].T.translation()[k], 1e-9) << "pose " << i;
		// Rotation: each quaternion component rounded by <= 5e-10; matrix
		// entries are quadratic in q with coefficients <= 2 over 4 terms, so
		// |dR| <= ~4e-9 before renormalisation; 1e-8 bounds it.
		EXPECT_LT(rotDiff(back[i].T, traj[i].T), 1e-8) << "pose " << i;
	}
}

TEST(IoTum, BadLinesNameFileAndLine)
{
	const std::string dir = shadyloc::test::tempDir("tum_bad");
	const std::string path = dir + "/bad.tum";
	{
		std::ofstream f(path);
		f << "# comment\n\n0.0 1 2 3 0 0 0 1\n0.1 1 2 3 0 0 1\n";
	}
	try
	{
		readTum(path);
		FAIL() << "a 7-value line was accepted";
	}
	catch (const std::exception& e)
	{
		EXPECT_NE(std::string(e.what()).find(path + "':4"), std::string::npos) << e.what();
	}
	{
		std::ofstream f(path);
		f << "0.0 1 2 3 0 0 0 2\n";	 // norm 2: not a unit quaternion
	}
	EXPECT_THROW(readTum(path), std::runtime_error);
	EXPECT_THROW(readTum(dir + "/missing.tum"), std::runtime_error);
}
