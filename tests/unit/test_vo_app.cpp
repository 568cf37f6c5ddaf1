/* Tests of `shadyloc vo` and `shadyloc traj-error` end to end, and of the
 * trajectory error metrics. */
#include <shadyloc/eval/TrajectoryError.h>
#include <shadyloc/io/Rawlog.h>
#include <shadyloc/io/Tum.h>
#include <shadyloc/sim/SyntheticCorridor.h>

#include "../support/Sequences.h"
#include "../support/TestSupport.h"

#include <mrpt/obs/CObservationStereoImages.h>

#include <filesystem>
#include <fstream>
#include <regex>

using namespace shadyloc;
namespace fs = std::filesystem;

namespace
{
/** A colour stereo rawlog of the corridor, and its ground truth (TUM). */
void writeCorridorRawlog(const std::string& rawlog, const std::string& gtTum, int n)
{
	const auto& seq = test::corridorSequence(50, 0.1);	// the ctest fixture's frames
	const auto& c = seq.calib;
	io::RawlogWriter w(rawlog);
	eval::Trajectory gt;
	const Eigen::Isometry3d T0inv = sim::SyntheticCorridor::examplePose(0).inverse();
	for (int k = 0; k < n; k++)
	{
		const Eigen::Isometry3d T = sim::SyntheticCorridor::examplePose(k);
		const cv::Mat &l = seq.left.at(k), &r = seq.right.at(k);
		const double t = 1000.0 + 0.1 * k;
		w.write(test::stereoObservation(l, r, c, t));
		gt.push_back({t, T0inv * T});
	}
	w.commit();
	io::writeTum(gtTum, gt);
}

double extract(const std::string& text, const std::string& re)
{
	std::smatch m;
	if (!std::regex_search(text, m, std::regex(re))) return -1;
	return std::stod(m[1]);
}
}  // namespace

TEST(VOApp, VoAndTrajErrorOnRawlogBothChannels)
{
	const std::string dir = test::tempDir("vo_app");
	const std::string rawlog = dir + "/corridor.rawlog", gt = dir + "/gt.tum";
	writeCorridorRawlog(rawlog, gt, 30);
	const std::string cfg = std::string(SHADYLOC_SOURCE_DIR) + "/config/vo.ini";
	for (const std::string ch : {"mono", "invariant"})
	{
		const std::string traj = dir + "/" + ch + ".tum", stats = dir + "/" + ch + ".csv";
		std::string out;
		ASSERT_EQ(
			test::runCommand(
				test::appPath() + " vo -i " + rawlog + " --channel " + ch + " -o " + traj + " -c " + cfg +
					" --stats " + stats + " --keyframes " + dir + "/kf.csv",
				&out),
			0)
			<< out;
		EXPECT_NE(out.find("converted on the fly"), std::string::npos) << out;
		const auto est = io::readTum(traj);
		ASSERT_EQ(est.size(), 30u);
		// The stats CSV: a header and one line per frame, all tracked here.
		std::ifstream f(stats);
		std::string line;
		std::getline(f, line);
		EXPECT_EQ(line.rfind("frame,timestamp,features,stereo_matches,tracked,inliers,keyframe,status", 0), 0u);
		int rows = 0, ok = 0;
		while (std::getline(f, line))
		{
			rows++;
			ok += line.find(",ok,") != std::string::npos || line.find(",first,") != std::string::npos;
		}
		EXPECT_EQ(rows, 30);
		EXPECT_EQ(ok, 30);
		ASSERT_EQ(test::runCommand(test::appPath() + " traj-error --gt " + gt + " --est " + traj, &out), 0)
			<< out;
		const double ate = extract(out, R"(ATE RMSE:\s+([0-9.]+))");
		const double kitti = extract(out, R"(KITTI-style average:\s+trans ([0-9.]+))");
		std::printf("[vo-app] %s: ATE %.4f m, KITTI-style %.3f %%\n", ch.c_str(), ate, kitti);
		// 3 m of travel: a few cm at most (see VOSynthetic for the bounds' reasoning).
		EXPECT_GE(ate, 0.0);
		EXPECT_LT(ate, 0.05);
		EXPECT_GE(kitti, 0.0);
		EXPECT_LT(kitti, ch == "mono" ? 1.0 : 3.0);
		EXPECT_NE(out.find("scaled down"), std::string::npos);
	}
}

TEST(VOApp, UsesFilteredChannelWhenPresent)
{
	const std::string dir = test::tempDir("vo_app_filtered");
	const std::string rawlog = dir + "/c.rawlog", gt = dir + "/gt.tum", filt = dir + "/f.rawlog";
	writeCorridorRawlog(rawlog, gt, 8);
	std::string out;
	ASSERT_EQ(test::runCommand(test::appPath() + " filter -q -i " + rawlog + " -o " + filt, &out), 0) << out;
	ASSERT_EQ(
		test::runCommand(test::appPath() + " vo -i " + filt + " --channel invariant -o " + dir + "/t.tum", &out), 0)
		<< out;
	EXPECT_NE(out.find("filtered observations 'CAMERA_inv'"), std::string::npos) << out;
	EXPECT_EQ(io::readTum(dir + "/t.tum").size(), 8u);
	// The filter record says which transform made the images: the same one as
	// the (default) config here, so no warning ...
	EXPECT_NE(out.find("invariant images made with the config's parameters"), std::string::npos) << out;
	EXPECT_EQ(out.find("warning"), std::string::npos) << out;
	// ... and a warning naming both when the config describes another one.
	std::ofstream(dir + "/other.ini") << "[invariant]\nalpha = 0.40\nbeta = 0.60\n";
	ASSERT_EQ(
		test::runCommand(
			test::appPath() + " vo -q -i " + filt + " --channel invariant -c " + dir + "/other.ini -o " + dir +
				"/t2.tum",
			&out),
		0)
		<< out;
	EXPECT_NE(out.find("warning: " + filt + ": its invariant images were made with alpha=0.48"), std::string::npos)
		<< out;
	EXPECT_NE(out.find("alpha=0.4 beta=0.6"), std::string::npos) << out;
}

TEST(VOApp, BadInputFailsCleanly)
{
	const std::string dir = test::tempDir("vo_app_bad");
	std::string out;
	EXPECT_NE(test::runCommand(test::appPath() + " vo -i " + dir + "/missing.rawlog -o " + dir + "/t.tum", &out), 0);
	EXPECT_NE(out.find("missing.rawlog"), std::string::npos) << out;
	EXPECT_FALSE(fs::exists(dir + "/t.tum"));
	// A grey rawlog cannot give the invariant channel: the error names the frame.
	const std::string rawlog = dir + "/grey.rawlog";
	{
		io::RawlogWriter w(rawlog);
		auto obs = test::syntheticStereoFrame(0);
		cv::Mat g(obs->imageLeft.asCvMatRef().size(), CV_8UC1, cv::Scalar(100));
		obs->imageLeft = mrpt::img::CImage(g, mrpt::img::DEEP_COPY);
		obs->imageRight = mrpt::img::CImage(g, mrpt::img::DEEP_COPY);
		w.write(*obs);
		w.commit();
	}
	EXPECT_NE(
		test::runCommand(test::appPath() + " vo -i " + rawlog + " --channel invariant -o " + dir + "/t.tum", &out), 0);
	EXPECT_NE(out.find("object #0"), std::string::npos) << out;
	EXPECT_FALSE(fs::exists(dir + "/t.tum"));
	// A bad option value names the section and key.
	std::ofstream(dir + "/bad.ini") << "[vo]\nmax_hamming = 999\n";
	EXPECT_NE(
		test::runCommand(test::appPath() + " vo -i " + rawlog + " -c " + dir + "/bad.ini -o " + dir + "/t.tum", &out), 0);
	EXPECT_NE(out.find("max_hamming"), std::string::npos) << out;
	EXPECT_NE(test::runCommand(test::appPath() + " traj-error --gt " + dir + "/nope.tum --est x.tum", &out), 0);
	EXPECT_NE(out.find("nope.tum"), std::string::npos) << out;
}

TEST(EvalTrajectoryError, KnownErrorsAreRecovered)
{
	// A 100 m straight-ish path; the estimate is the truth in another frame
	// (alignment must remove it) with a steady 1 % scale-like drift along
	// the path: KITTI-style translational error must come out as 1 %.
	eval::Trajectory gt, est;
	Eigen::Isometry3d Toff = Eigen::Isometry3d::Identity();
	Toff.linear() = Eigen::AngleAxisd(0.7, Eigen::Vector3d(0.2, 1, 0.1).normalized()).toRotationMatrix();
	Toff.translation() = Eigen::Vector3d(5, -2, 3);
	for (int k = 0; k <= 1000; k++)
	{
		Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
		T.translation() = Eigen::Vector3d(2 * std::sin(0.01 * k), 0, 0.1 * k);
		gt.push_back({0.1 * k, T});
		Eigen::Isometry3d E = T;
		E.translation().z() *= 1.01;
		est.push_back({0.1 * k + 0.001, Toff * E});  // 1 ms clock offset: within max_dt
	}
	const auto r = eval::computeErrors(gt, est);
	EXPECT_EQ(r.matched, 1001u);
	EXPECT_NEAR(r.length_scale, r.path_length / 1000, 1e-12);
	ASSERT_FALSE(r.segments.empty());
	// The path is mostly along z, so the drift of each segment is ~1 % of its length.
	EXPECT_NEAR(r.kitti_trans_pct, 1.0, 0.05);
	EXPECT_NEAR(r.kitti_rot_deg_per_m, 0.0, 1e-6);
	// ATE after alignment: the stretch of 1 m over 100 m, centred, is about
	// +-0.5 m at the ends: RMSE ~ 1 m / sqrt(12) = 0.29 m.
	EXPECT_NEAR(r.ate_rmse, 0.29, 0.03);
	// Identity: zero everything.
	const auto z = eval::computeErrors(gt, gt);
	EXPECT_LT(z.ate_rmse, 1e-9);
	EXPECT_LT(z.kitti_trans_pct, 1e-9);
	// Nothing associates: a clear error.
	eval::Trajectory late = gt;
	for (auto& p : late) p.t += 100;
	EXPECT_THROW(eval::computeErrors(gt, late), std::runtime_error);
}
