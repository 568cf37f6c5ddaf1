/* ShadyLoc — a diagnostic of one localiser on a live run with ground truth
 * (docs/localisation.md, "The other lane"). For every STEP-th live frame it
 * takes the map keyframe nearest the live frame by ground truth and the true
 * pose of the live camera in it, and reports what each stage of the
 * localiser makes of that keyframe when the prediction is the truth:
 *   visible  landmarks of the keyframe that project into the live image;
 *   detected ... with a live measurement within 2 px of the true projection;
 *   brief_ok ... whose BRIEF distance to that measurement is <= max_hamming;
 *   gate     BRIEF matches of the active search (gate around the truth,
 *            prediction sigma 0.1 m, 1 deg), and how many are right (< 3 px);
 *   refined  correspondences after patch refinement, and how many are right;
 *   inliers  RANSAC + solve inliers; status of a fresh localiser seeded by
 *            the truth; the global search's verdict for the frame;
 *   with_normal, brief_ok_warped, patch_ok_warped, hamming, hamming_warped
 *            the detected landmarks with a surface normal, and BRIEF and
 *            the patch through their plane's warp at the truth against as
 *            they are (mean Hamming distances);
 *   patch_all, patch_all_warped  landmarks whose patch, climbed to from the
 *            true projection whether a corner was detected there or not,
 *            is found within 1.5 px, unwarped and warped;
 *   offset_mean_x/y_px, offset_rms_px  the right refined correspondences'
 *            offsets from their true projection: mean and RMS.
 * Per bin of the landmarks' scale change s = depth in keyframe / depth in
 * live frame (s > 1: the live view is closer, the patch looks larger) it
 * adds up detected, brief_ok and refined-right landmarks.
 *
 *   localise_probe MAP LIVE.rawlog LIVE.tum CHANNEL STEP CONFIG.ini...
 *
 * With SHADYLOC_PROBE_DUMP=FILE it also writes each probed frame's refined
 * correspondences; `localise_probe --joint DUMP_A DUMP_B CONFIG.ini...`
 * solves two such dumps' frames (two channels of one run) separately and
 * in one solve, with each error against the truth.
 *
 * Prints CSV (one row per probed frame), then the scale table, then the
 * right refined correspondences by landmark depth in the live frame (their
 * RMS offset in (uL, v) and in uR from the map landmark's true projection). A diagnostic
 * for developers: not part of the test suite. */
#include <shadyloc/Registration.h>
#include <shadyloc/core/Settings.h>
#include <shadyloc/features/Brief.h>
#include <shadyloc/features/PatchWarp.h>
#include <shadyloc/io/StereoFrameSource.h>
#include <shadyloc/io/Tum.h>
#include <shadyloc/localisation/LocalisationSystem.h>
#include <shadyloc/localisation/StereoLocaliser.h>
#include <shadyloc/vo/KeyframeMatcher.h>
#include <shadyloc/vo/RelativePoseEstimator.h>

#include <mrpt/config/CConfigFileMemory.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <type_traits>
#include <fstream>
#include <iostream>
#include <map>
#include <sstream>

using namespace shadyloc;

namespace
{
constexpr double kDeg = M_PI / 180.0;

struct TBin
{
	int visible = 0, detected = 0, brief_ok = 0, refined_right = 0;
	long hamming_sum = 0;
};

/** fn(data, count) over a correspondence's fields, in one order. */
template <typename C, typename F>
void forEachField(C& c, F&& fn)
{
	fn(c.P_ref.data(), 3);
	fn(c.cov_ref.data(), 9);
	fn(c.z_ref.data(), 3);
	static_assert(sizeof(geometry::TStereoCalib) == 6 * sizeof(double), "fx, fy, cx, cy, cxR, baseline in a row");
	fn(&c.calib_ref.fx, 6);
	fn(c.z_curr.data(), 3);
	fn(c.P_curr.data(), 3);
}

/** One probed frame's refined correspondences and the true T_live_kf, as
 * raw bytes (a developer's scratch file, read back by --joint on the same
 * machine; TStereoCorrespondence is trivially copyable). */
void dumpFrame(std::ofstream& out, size_t frame, const Eigen::Isometry3d& T_live_kf, const geometry::TStereoCalib& calib,
			   const std::vector<geometry::TStereoCorrespondence>& corr)
{
	static_assert(std::is_trivially_copyable_v<geometry::TStereoCalib>);
	const uint64_t f = frame, n = corr.size();
	out.write(reinterpret_cast<const char*>(&f), sizeof f);
	out.write(reinterpret_cast<const char*>(T_live_kf.matrix().data()), 16 * sizeof(double));
	out.write(reinterpret_cast<const char*>(&calib), sizeof calib);
	out.write(reinterpret_cast<const char*>(&n), sizeof n);
	for (const auto& c : corr) forEachField(c, [&](const double* p, size_t k) {
		out.write(reinterpret_cast<const char*>(p), static_cast<std::streamsize>(k * sizeof(double)));
	});
}

struct TDumpedFrame
{
	Eigen::Isometry3d T_live_kf;
	geometry::TStereoCalib calib;
	std::vector<geometry::TStereoCorrespondence> corr;
};

std::map<uint64_t, TDumpedFrame> readDump(const std::string& path)
{
	std::ifstream in(path, std::ios::binary);
	if (!in) throw std::runtime_error("cannot read '" + path + "'");
	std::map<uint64_t, TDumpedFrame> frames;
	uint64_t f = 0, n = 0;
	while (in.read(reinterpret_cast<char*>(&f), sizeof f))
	{
		TDumpedFrame d;
		in.read(reinterpret_cast<char*>(d.T_live_kf.matrix().data()), 16 * sizeof(double));
		in.read(reinterpret_cast<char*>(&d.calib), sizeof d.calib);
		in.read(reinterpret_cast<char*>(&n), sizeof n);
		d.corr.resize(n);
		for (auto& c : d.corr) forEachField(c, [&](double* p, size_t k) {
			in.read(reinterpret_cast<char*>(p), static_cast<std::streamsize>(k * sizeof(double)));
		});
		if (!in) throw std::runtime_error("'" + path + "' is truncated");
		frames[f] = std::move(d);
	}
	return frames;
}

/** --joint: each frame solved on channel A's correspondences, on B's, and
 * on both in one solve (the same keyframe: the probe picks it by the truth),
 * with the error of each against the true pose. */
int jointMode(const std::string& dumpA, const std::string& dumpB, const mrpt::config::CConfigFileBase& cfg)
{
	const auto A = readDump(dumpA), B = readDump(dumpB);
	const auto lo = localisation::localiserOptionsFor(cfg, "mono", "localiser");
	const vo::RelativePoseEstimator estimator(localisation::estimatorOptionsFor(lo));
	std::printf("frame,a_corr,b_corr,a_inliers,a_err_m,b_inliers,b_err_m,joint_inliers,joint_err_m\n");
	auto solve = [&](const std::vector<geometry::TStereoCorrespondence>& c, const TDumpedFrame& d, uint64_t seed,
					 int& inliers) {
		inliers = 0;
		if (c.size() < 6) return std::nan("");
		vo::TRelativePoseInput pi;
		pi.corr = &c;
		pi.calib = d.calib;
		pi.seed = static_cast<uint32_t>(seed);
		vo::TRelativePoseOutput out;
		estimator.estimate(pi, out);
		if (!out.ok()) return std::nan("");
		inliers = static_cast<int>(out.inliers);
		return (out.T_curr_ref.translation() - d.T_live_kf.translation()).norm();
	};
	for (const auto& [f, a] : A)
	{
		const auto it = B.find(f);
		if (it == B.end()) continue;
		const auto& b = it->second;
		auto both = a.corr;
		both.insert(both.end(), b.corr.begin(), b.corr.end());
		int ia = 0, ib = 0, ij = 0;
		const double ea = solve(a.corr, a, f, ia), eb = solve(b.corr, a, f, ib), ej = solve(both, a, f, ij);
		std::printf("%llu,%zu,%zu,%d,%.4f,%d,%.4f,%d,%.4f\n", static_cast<unsigned long long>(f), a.corr.size(),
					b.corr.size(), ia, ea, ib, eb, ij, ej);
	}
	return 0;
}

int binOf(double s)
{
	// log2 bins of width 0.25 around 1: ... [0.71,0.84) [0.84,1) [1,1.19) [1.19,1.41) ...
	return static_cast<int>(std::floor(std::log2(s) / 0.25));
}
}  // namespace

int main(int argc, char** argv)
{
	const bool joint = argc >= 5 && std::string(argv[1]) == "--joint";
	if (argc < 7 && !joint)
	{
		std::cerr << "usage: localise_probe MAP LIVE.rawlog LIVE.tum CHANNEL STEP CONFIG.ini...\n"
					 "       localise_probe --joint DUMP_A DUMP_B CONFIG.ini...\n";
		return 2;
	}
	try
	{
		registerAllClasses();
		// The config files from argv[first] on, layered as the commands' -c.
		auto configFrom = [&](int first) {
			return mrpt::config::CConfigFileMemory(
				core::layeredConfigText(std::vector<std::string>(argv + first, argv + argc)));
		};
		if (joint) return jointMode(argv[2], argv[3], configFrom(4));
		const std::string mapPath = argv[1], livePath = argv[2], tumPath = argv[3], channel = argv[4];
		const int step = std::max(1, std::atoi(argv[5]));
		const auto cfg = configFrom(6);
		auto map = CKeyframeMap::LoadFromFile(mapPath);
		const auto setup = localisation::LocalisationSystem::SetupFromConfig(cfg, {channel}, 1, "probe");
		const localisation::LocalisationSystem::TChannelSetup* cs = nullptr;
		for (const auto& c : setup.channels)
			if (c.channel.label == channel) cs = &c;
		if (!cs) throw std::runtime_error("no channel '" + channel + "' in the config");
		const auto& lo = cs->localiser;
		features::StereoFeatureExtractor extractor(cs->features);
		const features::BriefExtractor brief(cs->features.brief_patch_size, cs->features.brief_seed);
		const size_t ch = map->channelIndex(channel);
		(void)ch;

		io::Trajectory gt = io::readTum(tumPath);
		io::sortByTime(gt);

		// The matchers and estimator the localiser uses (gate around the truth).
		vo::TKeyframeMatcherOptions mo = localisation::matcherOptionsFor(lo, localisation::SearchMode::Gate);
		// The ceiling as the localiser applied it before gate_landmark_max_px:
		// every landmark whose gate exceeds gate_max_px counts as overflowing.
		mo.gate_landmark_max_px = 0;
		const vo::KeyframeMatcher matcher(mo);
		// The same with the gate clamped to a wide ceiling: what BRIEF and the
		// patch would find if the gate did not overflow.
		vo::TKeyframeMatcherOptions moWide = mo;
		moWide.gate_clamp = true;
		moWide.gate_max_px = 150;
		const vo::KeyframeMatcher wideMatcher(moWide);
		const vo::RelativePoseEstimator estimator(localisation::estimatorOptionsFor(lo));
		geometry::Matrix6d predCov = geometry::Matrix6d::Zero();
		predCov.diagonal() << 0.01, 0.01, 0.01, kDeg * kDeg, kDeg * kDeg, kDeg * kDeg;

		io::TStereoFrameSourceOptions so;
		so.acceptLabel = io::labelWithoutSuffixes({"_mono", "_inv", "_lin"});
		io::StereoFrameSource source(livePath, so);
		io::TStereoFrame fr;
		std::map<int, TBin> bins;
		// SHADYLOC_PROBE_DUMP=FILE: the refined correspondences of each probed
		// frame, for --joint.
		std::ofstream dump;
		if (const char* d = std::getenv("SHADYLOC_PROBE_DUMP")) dump.open(d, std::ios::binary);
		// Right refined correspondences by the landmark's depth in the live
		// frame: count and summed squared offset (uL, v) and uR error.
		struct TDepthBin
		{
			int n = 0;
			double sq = 0, sqR = 0;
		};
		const std::vector<double> depthEdges = {0, 5, 10, 20, 40, 1e9};
		std::vector<TDepthBin> depthBins(depthEdges.size() - 1);
		std::printf(
			"frame,kf,dist_m,lateral_m,visible,detected,brief_ok,patch_ok,gate_overflow,gate_median_px,exact_gate_overflow,exact_gate_median_px,gate_matches,"
			"gate_right,refined,refined_right,inliers,wide_matches,wide_right,wide_refined_right,wide_inliers,status,global,"
			"with_normal,brief_ok_warped,patch_ok_warped,hamming,hamming_warped,patch_all,patch_all_warped,"
			"offset_mean_x_px,offset_mean_y_px,offset_rms_px\n");
		while (source.next(fr))
		{
			if (static_cast<int>(fr.index) % step) continue;
			// ground truth of the frame
			const io::TStampedPose* g = nullptr;
			for (const auto& p : gt)
				if (std::abs(p.t - fr.timestamp) <= 0.01) g = &p;
			if (!g) continue;
			// nearest keyframe by ground truth, heading within 30 deg
			int best = -1;
			double bestD = 1e9;
			for (const auto& k : map->keyframes())
			{
				if (!k.T_gt_kf) continue;
				const double ang =
					std::acos(std::clamp(k.T_gt_kf->linear().col(2).dot(g->T.linear().col(2)), -1.0, 1.0)) / kDeg;
				const double d = (k.T_gt_kf->translation() - g->T.translation()).norm();
				if (ang < 30 && d < bestD)
				{
					bestD = d;
					best = static_cast<int>(k.id);
				}
			}
			if (best < 0) continue;
			const auto& kf = map->keyframe(static_cast<uint32_t>(best));
			const Eigen::Isometry3d T_kf_live = kf.T_gt_kf->inverse() * g->T;
			const Eigen::Isometry3d T_live_kf = T_kf_live.inverse();

			cv::Mat gl, gr;
			cs->channel.convertPair(fr.left, fr.right, gl, gr);
			features::TStereoFrame meas;
			extractor.process(gl, gr, fr.calib, meas);
			const auto& lms = map->measurements(kf.id, channel);

			// ---- per landmark, with the truth
			int visible = 0, detected = 0, briefOk = 0, patchOk = 0, withNormal = 0, briefOkW = 0, patchOkW = 0;
			long hamSum = 0, hamSumW = 0;
			int patchAll = 0, patchAllW = 0;
			std::vector<Eigen::Vector2d> truthPx(lms.size(), Eigen::Vector2d(-1e9, -1e9));
			std::vector<double> scale(lms.size(), 0);
			for (size_t j = 0; j < lms.size(); j++)
			{
				const Eigen::Vector3d p = T_live_kf * lms[j].P;
				if (p.z() < 0.5) continue;
				const double u = fr.calib.fx * p.x() / p.z() + fr.calib.cx, v = fr.calib.fy * p.y() / p.z() + fr.calib.cy;
				if (u < 0 || v < 0 || u >= gl.cols || v >= gl.rows) continue;
				truthPx[j] = Eigen::Vector2d(u, v);
				scale[j] = lms[j].P.z() / p.z();
				visible++;
				TBin& b = bins[binOf(scale[j])];
				b.visible++;
				{
					// Direct patch search at the true projection, detected or not.
					const int xi0 = static_cast<int>(std::lround(u)), yi0 = static_cast<int>(std::lround(v));
					float xa, ya;
					if (xi0 >= 16 && yi0 >= 16 && xi0 < gl.cols - 16 && yi0 < gl.rows - 16)
					{
						patchAll += features::locatePatch(lms[j].patch, gl, xi0, yi0, lo.refine_radius_px, lo.refine_min_zncc, lo.refine_iterations, xa, ya) && std::hypot(xa - u, ya - v) < 1.5;
						Eigen::Matrix2d A0;
						const bool hasA = !lms[j].normal.isZero() && features::planeInducedAffine(map->calibration(), fr.calib, T_live_kf, lms[j].P, lms[j].normal.cast<double>(), A0);
						patchAllW += features::locateWarpedPatch(lms[j].patch, gl, xi0, yi0, hasA ? A0 : Eigen::Matrix2d::Identity(), lo.refine_radius_px, lo.refine_min_zncc, lo.refine_iterations, xa, ya) && std::hypot(xa - u, ya - v) < 1.5;
					}
				}
				int nearest = -1;
				double nd = 4.0;
				for (size_t i = 0; i < meas.meas.size(); i++)
				{
					const double d2 = std::pow(meas.meas[i].uL - u, 2) + std::pow(meas.meas[i].v - v, 2);
					if (d2 < nd)
					{
						nd = d2;
						nearest = static_cast<int>(i);
					}
				}
				if (nearest < 0) continue;
				detected++;
				// The stored patch at the true position: does refinement accept it?
				float xs = 0, ys = 0;
				const int xi = static_cast<int>(std::lround(u)), yi = static_cast<int>(std::lround(v));
				if (xi >= features::kPatchSize && yi >= features::kPatchSize && xi < gl.cols - features::kPatchSize &&
					yi < gl.rows - features::kPatchSize &&
					features::locatePatch(
						lms[j].patch, gl, xi, yi, lo.refine_radius_px, lo.refine_min_zncc, lo.refine_iterations, xs, ys) &&
					std::hypot(xs - u, ys - v) < 3)
					patchOk++;
				b.detected++;
				const auto& near = meas.meas[static_cast<size_t>(nearest)];
				const int h = features::hamming(lms[j].desc, near.desc);
				b.hamming_sum += h;
				// Through the landmark's plane-induced warp at the true pose.
				Eigen::Matrix2d A;
				if (!lms[j].normal.isZero() &&
					features::planeInducedAffine(
						map->calibration(), fr.calib, T_live_kf, lms[j].P, lms[j].normal.cast<double>(), A))
				{
					withNormal++;
					features::TBriefDescriptor wd;
					const features::WarpedBriefPattern wp(brief, A);
					const int hw = wp.compute(meas.smoothed, static_cast<int>(near.uL), static_cast<int>(near.v), wd)
									   ? features::hamming(lms[j].desc, wd)
									   : 256;
					hamSum += h;
					hamSumW += hw;
					briefOkW += hw <= lo.max_hamming;
					if (xi >= 16 && yi >= 16 && xi < gl.cols - 16 && yi < gl.rows - 16 &&
						features::locateWarpedPatch(
							lms[j].patch, gl, xi, yi, A, lo.refine_radius_px, lo.refine_min_zncc, lo.refine_iterations,
							xs, ys) &&
						std::hypot(xs - u, ys - v) < 3)
						patchOkW++;
				}
				if (h <= lo.max_hamming)
				{
					briefOk++;
					b.brief_ok++;
				}
			}

			// ---- the localiser's stages with the truth as prediction
			vo::TKeyframeMatchInput mi;
			mi.landmarks = &lms;
			mi.calib_kf = map->calibration();
			mi.frame = &meas;
			mi.calib = fr.calib;
			mi.T_curr_kf_pred = T_live_kf;
			mi.cov_T_curr_kf_pred = predCov;
			mi.brief = &brief;
			std::vector<int> matchOf;
			matcher.searchDescriptors(mi, 0, matchOf);
			int gateMatches = 0, gateRight = 0;
			for (size_t j = 0; j < lms.size(); j++)
				if (matchOf[j] >= 0)
				{
					gateMatches++;
					const auto& m = meas.meas[static_cast<size_t>(matchOf[j])];
					gateRight += (Eigen::Vector2d(m.uL, m.v) - truthPx[j]).norm() < 3;
				}
			vo::TKeyframeMatchOutput out;
			matcher.match(mi, out);
			int refinedRight = 0;
			// The right ones' offsets from the truth: a mean comparable to
			// the RMS is an error shared by many correspondences at once.
			Eigen::Vector2d offSum = Eigen::Vector2d::Zero();
			double offSq = 0;
			for (size_t c = 0; c < out.corr.size(); c++)
			{
				const size_t j = static_cast<size_t>(out.landmark[c]);
				const Eigen::Vector2d off = out.corr[c].z_curr.head<2>() - truthPx[j];
				if (off.norm() < 3)
				{
					refinedRight++;
					bins[binOf(scale[j])].refined_right++;
					offSum += off;
					offSq += off.squaredNorm();
					const Eigen::Vector3d Pl = T_live_kf * lms[j].P;
					const Eigen::Vector3d zTrue = fr.calib.project(Pl);
					size_t d = 0;
					while (d + 2 < depthEdges.size() && Pl.z() >= depthEdges[d + 1]) d++;
					depthBins[d].n++;
					depthBins[d].sq += off.squaredNorm();
					depthBins[d].sqR += std::pow(out.corr[c].z_curr.z() - zTrue.z(), 2);
				}
			}
			if (dump.is_open()) dumpFrame(dump, fr.index, T_live_kf, fr.calib, out.corr);
			const Eigen::Vector2d offMean = offSum / std::max(1, refinedRight);
			const double offRms = std::sqrt(offSq / std::max(1, refinedRight));
			auto solveInliers = [&](const vo::TKeyframeMatchOutput& o) {
				if (o.corr.size() < 6) return 0;
				vo::TRelativePoseInput pi;
				pi.corr = &o.corr;
				pi.calib = fr.calib;
				pi.seed = static_cast<uint32_t>(fr.index);
				vo::TRelativePoseOutput pout;
				estimator.estimate(pi, pout);
				return pout.ok() ? static_cast<int>(pout.inliers) : 0;
			};
			const int inliers = solveInliers(out);
			std::vector<int> wideOf;
			wideMatcher.searchDescriptors(mi, 0, wideOf);
			int wideMatches = 0, wideRight = 0;
			for (size_t j = 0; j < lms.size(); j++)
				if (wideOf[j] >= 0)
				{
					wideMatches++;
					const auto& m = meas.meas[static_cast<size_t>(wideOf[j])];
					wideRight += (Eigen::Vector2d(m.uL, m.v) - truthPx[j]).norm() < 3;
				}
			vo::TKeyframeMatchOutput wout;
			wideMatcher.match(mi, wout);
			int wideRefinedRight = 0;
			for (size_t c = 0; c < wout.corr.size(); c++)
				wideRefinedRight +=
					(wout.corr[c].z_curr.head<2>() - truthPx[static_cast<size_t>(wout.landmark[c])]).norm() < 3;
			const int wideInliers = solveInliers(wout);
			// The gate with an exact prediction: the landmarks' own covariance
			// (stereo depth from the keyframe's baseline) and the pixel noise.
			vo::TKeyframeMatchInput miExact = mi;
			miExact.cov_T_curr_kf_pred = geometry::Matrix6d::Zero();
			vo::TGateStats exactGate;
			std::vector<int> exactOf;
			matcher.searchDescriptors(miExact, 0, exactOf, &exactGate);
			localisation::StereoLocaliser loc(*map, channel, lo);
			localisation::TLocaliserInput in;
			in.frame = fr.index;
			in.timestamp = fr.timestamp;
			in.meas = &meas;
			in.calib = fr.calib;
			in.prediction.valid = true;
			in.prediction.kf = kf.id;
			in.prediction.T_kf_live = T_kf_live;
			in.prediction.cov = predCov;
			const auto res = loc.localise(in);
			const auto place = loc.globalSearch(meas, fr.calib, static_cast<uint32_t>(fr.index));
			std::string gs = place.ok ? "ok:kf" + std::to_string(place.pose.kf) + ":" + std::to_string(place.inliers)
									  : place.why;
			for (auto& c : gs)
				if (c == ',') c = ';';
			std::printf(
				"%zu,%u,%.2f,%.2f,%d,%d,%d,%d,%d,%.1f,%d,%.1f,%d,%d,%zu,%d,%d,%d,%d,%d,%d,%s,%s,%d,%d,%d,%.1f,%.1f,%d,%d,%.3f,%.3f,%.3f\n", fr.index, kf.id, bestD,
				T_kf_live.translation().x(), visible, detected, briefOk, patchOk, out.gate.overflow, out.gate.median_axis_px, exactGate.overflow,
				exactGate.median_axis_px,
				gateMatches, gateRight, out.corr.size(), refinedRight, inliers, wideMatches, wideRight, wideRefinedRight,
				wideInliers, localisation::toString(res.status).c_str(), gs.c_str(), withNormal, briefOkW, patchOkW,
				withNormal ? double(hamSum) / withNormal : 0.0, withNormal ? double(hamSumW) / withNormal : 0.0, patchAll, patchAllW,
				offMean.x(), offMean.y(), offRms);
			std::fflush(stdout);
		}
		std::printf("\nscale_bin_lo,scale_bin_hi,visible,detected,brief_ok,refined_right,mean_hamming\n");
		for (const auto& [k, b] : bins)
			std::printf(
				"%.2f,%.2f,%d,%d,%d,%d,%.1f\n", std::pow(2.0, 0.25 * k), std::pow(2.0, 0.25 * (k + 1)), b.visible,
				b.detected, b.brief_ok, b.refined_right, b.detected ? double(b.hamming_sum) / b.detected : 0.0);
		std::printf("\ndepth_lo_m,depth_hi_m,refined_right,offset_rms_px,uR_rms_px\n");
		for (size_t d = 0; d < depthBins.size(); d++)
			std::printf(
				"%.0f,%.0f,%d,%.3f,%.3f\n", depthEdges[d], depthEdges[d + 1], depthBins[d].n,
				std::sqrt(depthBins[d].sq / std::max(1, depthBins[d].n)), std::sqrt(depthBins[d].sqR / std::max(1, depthBins[d].n)));
		return 0;
	}
	catch (const std::exception& e)
	{
		std::cerr << "localise_probe: " << e.what() << "\n";
		return 1;
	}
}
