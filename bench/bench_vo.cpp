/* ShadyLoc — stereo VO speed per frame at 512x384 (the paper's Bumblebee2
 * resolution): each stage, the whole frame on one channel, and both channels
 * (mono + invariant) on two threads. Goals: one channel >= 50 Hz; both
 * channels together <= 1.3x one channel's wall time.
 *
 * Frames: the ray-cast corridor (sim::SyntheticCorridor), 24 frames played
 * forwards and backwards so the motion stays continuous while looping. */
#include <shadyloc/features/StereoFeatures.h>
#include <shadyloc/filters/Channel.h>
#include <shadyloc/filters/Filters.h>
#include <shadyloc/geometry/PoseSolver.h>
#include <shadyloc/sim/SyntheticCorridor.h>
#include <shadyloc/vo/KeyframeMatcher.h>
#include <shadyloc/vo/RelativePoseEstimator.h>
#include <shadyloc/vo/StereoVO.h>

#include <benchmark/benchmark.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/features2d.hpp>

#include <opencv2/core/utility.hpp>

#include <chrono>
#include <future>
#include <vector>

using namespace shadyloc;

namespace
{
constexpr int kFrames = 24;

struct TData
{
	geometry::TStereoCalib calib;
	std::vector<cv::Mat> colourL, colourR;
	std::vector<cv::Mat> monoL, monoR, invL, invR;
};

const TData& data()
{
	static const TData d = [] {
		TData d;
		sim::TCorridorOptions o;
		o.width = 512;
		o.height = 384;
		o.fx = 400;
		o.baseline = 0.12;	// Bumblebee2
		sim::SyntheticCorridor c(o);
		d.calib = c.calib();
		const auto mono = filters::defaultChannel("mono"), inv = filters::defaultChannel("invariant");
		for (int k = 0; k < kFrames; k++)
		{
			cv::Mat l, r, a, b;
			c.render(sim::SyntheticCorridor::examplePose(k), l, r, k);
			d.colourL.push_back(l);
			d.colourR.push_back(r);
			mono.convert(l, a);
			mono.convert(r, b);
			d.monoL.push_back(a.clone());
			d.monoR.push_back(b.clone());
			inv.convert(l, a);
			inv.convert(r, b);
			d.invL.push_back(a.clone());
			d.invR.push_back(b.clone());
		}
		return d;
	}();
	return d;
}

/** Real images: Middlebury Adirondack (quarter resolution, 718x496), 512x384
 * windows cropped at offsets moving 3 px right and 1 px down per frame (the
 * calibration is kept, so the VO sees a small rotation-like image motion).
 * Empty if the shared data is absent. */
struct TRealData
{
	geometry::TStereoCalib calib;
	features::TStereoFeatureOptions fopt;
	std::vector<cv::Mat> monoL, monoR, invL, invR;
};
const TRealData& realData()
{
	static const TRealData d = [] {
		TRealData d;
		const std::string dir = std::string(SHADYLOC_SHARED_DATA_DIR) + "/middlebury/Adirondack/";
		const cv::Mat l = cv::imread(dir + "im0.png", cv::IMREAD_COLOR), r = cv::imread(dir + "im1.png", cv::IMREAD_COLOR);
		if (l.empty() || r.empty()) return d;
		// calib.txt of Adirondack: cam0 cx 322.037, cam1 cx 375.308, f 1038.018, b 176.252 mm.
		d.calib.fx = d.calib.fy = 1038.018;
		d.calib.cx = 322.037;
		d.calib.cxR = 375.308;
		d.calib.cy = 243.393;
		d.calib.baseline = 0.176252;
		d.fopt.min_disparity = 50;	// measured 8..65 px + doffs 53.3
		d.fopt.max_disparity = 125;
		auto ip = image::InvariantParams::FromAlphaBeta(0.48, 0.5065);
		ip.linearisation = image::Linearisation::SRGB;
		const auto mono = filters::defaultChannel("mono");
		auto invFilter = CFilterInvariant::Create();
		invFilter->setParams(ip);
		const filters::TChannel inv{"invariant", invFilter};
		cv::Mat ml, mr, il, ir;
		mono.convert(l, ml);
		mono.convert(r, mr);
		inv.convert(l, il);
		inv.convert(r, ir);
		for (int k = 0; k < kFrames; k++)
		{
			const cv::Rect roi(20 + 3 * k, 40 + k, 512, 384);
			d.monoL.push_back(ml(roi).clone());
			d.monoR.push_back(mr(roi).clone());
			d.invL.push_back(il(roi).clone());
			d.invR.push_back(ir(roi).clone());
		}
		return d;
	}();
	return d;
}

/** 0, 1, ..., n-1, n-2, ..., 1, 0, 1, ...: continuous motion in a loop. */
int pingPong(int64_t i)
{
	const int64_t p = i % (2 * (kFrames - 1));
	return static_cast<int>(p < kFrames ? p : 2 * (kFrames - 1) - p);
}

void addStageCounters(benchmark::State& st, const vo::TVOTimings& sum, int64_t n)
{
	const double k = 1.0 / std::max<int64_t>(1, n);
	// By stage: the feature extractor (detect, stereo, describe), the
	// keyframe matcher, the relative-pose estimator (RANSAC, solve).
	st.counters["ms_extract_detect"] = sum.detect * k;
	st.counters["ms_extract_stereo"] = sum.stereo * k;
	st.counters["ms_extract_describe"] = sum.describe * k;
	st.counters["ms_keyframe_matcher"] = sum.match * k;
	st.counters["ms_relpose_ransac"] = sum.ransac * k;
	st.counters["ms_relpose_solve"] = sum.solve * k;
	st.counters["ms_total"] = sum.total * k;
}
void accumulate(vo::TVOTimings& s, const vo::TVOTimings& t)
{
	s.detect += t.detect;
	s.stereo += t.stereo;
	s.describe += t.describe;
	s.match += t.match;
	s.ransac += t.ransac;
	s.solve += t.solve;
	s.total += t.total;
}

/** One channel, whole VO frame; stage times as counters [ms]. */
void BM_VOFrame(benchmark::State& st, bool invariant)
{
	const auto& d = data();
	const auto& L = invariant ? d.invL : d.monoL;
	const auto& R = invariant ? d.invR : d.monoR;
	vo::StereoVO vo;
	vo.setMinLoggingLevel(mrpt::system::LVL_ERROR);
	vo::TVOTimings sum;
	int64_t i = 0, untracked = 0;
	for (auto _ : st)
	{
		const int k = pingPong(i);
		const auto r = vo.process(L[k], R[k], d.calib, 0.1 * i);
		accumulate(sum, r.ms);
		untracked += !vo::isTracked(r.status);
		i++;
	}
	addStageCounters(st, sum, i);
	st.counters["untracked"] = static_cast<double>(untracked);
	st.counters["Hz"] = benchmark::Counter(static_cast<double>(i), benchmark::Counter::kIsRate);
}
BENCHMARK_CAPTURE(BM_VOFrame, mono, false)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK_CAPTURE(BM_VOFrame, invariant, true)->Unit(benchmark::kMillisecond)->UseRealTime();

/** Both channels on two threads (mono on a worker, invariant here): wall time per frame. */
void BM_VOFrameBothParallel(benchmark::State& st)
{
	const auto& d = data();
	vo::StereoVO voM, voI;
	voM.setMinLoggingLevel(mrpt::system::LVL_ERROR);
	voI.setMinLoggingLevel(mrpt::system::LVL_ERROR);
	int64_t i = 0, untracked = 0;
	for (auto _ : st)
	{
		const int k = pingPong(i);
		auto fm = std::async(std::launch::async, [&] { return voM.process(d.monoL[k], d.monoR[k], d.calib, 0.1 * i); });
		const auto ri = voI.process(d.invL[k], d.invR[k], d.calib, 0.1 * i);
		const auto rm = fm.get();
		untracked += !vo::isTracked(rm.status) + !vo::isTracked(ri.status);
		i++;
	}
	st.counters["untracked"] = static_cast<double>(untracked);
	st.counters["Hz"] = benchmark::Counter(static_cast<double>(i), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_VOFrameBothParallel)->Unit(benchmark::kMillisecond)->UseRealTime();

/** Both channels one after the other on one thread (the reference for the parallel gain). */
void BM_VOFrameBothSerial(benchmark::State& st)
{
	const auto& d = data();
	vo::StereoVO voM, voI;
	voM.setMinLoggingLevel(mrpt::system::LVL_ERROR);
	voI.setMinLoggingLevel(mrpt::system::LVL_ERROR);
	int64_t i = 0;
	for (auto _ : st)
	{
		const int k = pingPong(i);
		benchmark::DoNotOptimize(voM.process(d.monoL[k], d.monoR[k], d.calib, 0.1 * i));
		benchmark::DoNotOptimize(voI.process(d.invL[k], d.invR[k], d.calib, 0.1 * i));
		i++;
	}
}
BENCHMARK(BM_VOFrameBothSerial)->Unit(benchmark::kMillisecond)->UseRealTime();

/** One channel on the real (Middlebury) crops. */
void BM_VOFrameReal(benchmark::State& st, bool invariant)
{
	const auto& d = realData();
	if (d.monoL.empty())
	{
		st.SkipWithError("../shared/data/middlebury/Adirondack absent");
		return;
	}
	const auto& L = invariant ? d.invL : d.monoL;
	const auto& R = invariant ? d.invR : d.monoR;
	vo::StereoVO vo(vo::TStereoVOOptions(), d.fopt);
	vo.setMinLoggingLevel(mrpt::system::LVL_ERROR);
	vo::TVOTimings sum;
	int64_t i = 0, untracked = 0, stereo = 0;
	for (auto _ : st)
	{
		const int k = pingPong(i);
		const auto r = vo.process(L[k], R[k], d.calib, 0.1 * i);
		accumulate(sum, r.ms);
		untracked += !vo::isTracked(r.status);
		stereo += r.stereo;
		i++;
	}
	addStageCounters(st, sum, i);
	st.counters["stereo"] = double(stereo) / std::max<int64_t>(1, i);
	st.counters["untracked"] = static_cast<double>(untracked);
}
BENCHMARK_CAPTURE(BM_VOFrameReal, mono, false)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK_CAPTURE(BM_VOFrameReal, invariant, true)->Unit(benchmark::kMillisecond)->UseRealTime();

/** Both channels on two threads on the real crops. */
void BM_VOFrameRealBothParallel(benchmark::State& st)
{
	const auto& d = realData();
	if (d.monoL.empty())
	{
		st.SkipWithError("../shared/data/middlebury/Adirondack absent");
		return;
	}
	vo::StereoVO voM(vo::TStereoVOOptions(), d.fopt), voI(vo::TStereoVOOptions(), d.fopt);
	voM.setMinLoggingLevel(mrpt::system::LVL_ERROR);
	voI.setMinLoggingLevel(mrpt::system::LVL_ERROR);
	int64_t i = 0;
	for (auto _ : st)
	{
		const int k = pingPong(i);
		auto fm = std::async(std::launch::async, [&] { return voM.process(d.monoL[k], d.monoR[k], d.calib, 0.1 * i); });
		benchmark::DoNotOptimize(voI.process(d.invL[k], d.invR[k], d.calib, 0.1 * i));
		fm.get();
		i++;
	}
}
BENCHMARK(BM_VOFrameRealBothParallel)->Unit(benchmark::kMillisecond)->UseRealTime();

/** The goal's ratio, measured in one loop: per iteration, one mono frame
 * alone, then a mono and an invariant frame on two threads (separate VO
 * instances), then one invariant frame alone. Counters: ratio =
 * wall(both) / wall(mono alone), ratio_vs_inv = wall(both) / wall(invariant alone). */
void BM_BothOverOneRatio(benchmark::State& st, bool real)
{
	const auto& syn = data();
	const auto& rd = realData();
	if (real && rd.monoL.empty())
	{
		st.SkipWithError("../shared/data/middlebury/Adirondack absent");
		return;
	}
	const auto& monoL = real ? rd.monoL : syn.monoL;
	const auto& monoR = real ? rd.monoR : syn.monoR;
	const auto& invL = real ? rd.invL : syn.invL;
	const auto& invR = real ? rd.invR : syn.invR;
	const auto& calib = real ? rd.calib : syn.calib;
	const features::TStereoFeatureOptions fopt = real ? rd.fopt : features::TStereoFeatureOptions();
	const vo::TStereoVOOptions vopt;
	vo::StereoVO solo(vopt, fopt), soloI(vopt, fopt), voM(vopt, fopt), voI(vopt, fopt);
	for (auto* v : {&solo, &soloI, &voM, &voI}) v->setMinLoggingLevel(mrpt::system::LVL_ERROR);
	using C = std::chrono::steady_clock;
	double one = 0, oneI = 0, both = 0;
	int64_t i = 0;
	for (auto _ : st)
	{
		const int k = pingPong(i);
		auto t0 = C::now();
		auto fm = std::async(std::launch::async, [&] { return voM.process(monoL[k], monoR[k], calib, 0.1 * i); });
		benchmark::DoNotOptimize(voI.process(invL[k], invR[k], calib, 0.1 * i));
		fm.get();
		auto t1 = C::now();
		benchmark::DoNotOptimize(solo.process(monoL[k], monoR[k], calib, 0.1 * i));
		auto t2 = C::now();
		benchmark::DoNotOptimize(soloI.process(invL[k], invR[k], calib, 0.1 * i));
		auto t3 = C::now();
		both += std::chrono::duration<double, std::milli>(t1 - t0).count();
		one += std::chrono::duration<double, std::milli>(t2 - t1).count();
		oneI += std::chrono::duration<double, std::milli>(t3 - t2).count();
		i++;
	}
	st.counters["ms_one"] = one / std::max<int64_t>(1, i);
	st.counters["ms_both"] = both / std::max<int64_t>(1, i);
	st.counters["ms_one_inv"] = oneI / std::max<int64_t>(1, i);
	st.counters["ratio"] = one > 0 ? both / one : 0;  // vs the mono channel alone
	st.counters["ratio_vs_inv"] = oneI > 0 ? both / oneI : 0;  // vs the invariant channel alone
}
BENCHMARK_CAPTURE(BM_BothOverOneRatio, synthetic, false)->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(3.0);
BENCHMARK_CAPTURE(BM_BothOverOneRatio, middlebury, true)->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(3.0);

/** Stage micro-benchmarks, frame 0. */
void BM_StageFastGrid(benchmark::State& st, bool invariant)
{
	const auto& d = data();
	const cv::Mat& L = invariant ? d.invL[0] : d.monoL[0];
	const cv::Mat& R = invariant ? d.invR[0] : d.monoR[0];
	features::TStereoFeatureOptions o;
	std::vector<cv::KeyPoint> kl, kr, raw;
	for (auto _ : st)
	{
		features::detectFastGrid(L, o.fast_threshold, o.grid_cols, o.grid_rows, o.max_per_cell, 17, kl);
		features::detectFastGrid(R, o.fast_threshold, o.grid_cols, o.grid_rows, o.max_per_cell_right, 6, kr);
	}
	cv::FAST(L, raw, o.fast_threshold, true);
	st.counters["raw_left"] = static_cast<double>(raw.size());
	st.counters["left"] = static_cast<double>(kl.size());
	st.counters["right"] = static_cast<double>(kr.size());
}
BENCHMARK_CAPTURE(BM_StageFastGrid, mono, false)->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_StageFastGrid, invariant, true)->Unit(benchmark::kMicrosecond);

/** The invariant channel's corners as shipped (ORB pyramid: 3 levels of
 * 1.4, FAST threshold 5), both images of a pair: CornerDescriber (the right
 * image's candidates without orientations, the left's measured only for the
 * corners the grid keeps) against cv::ORB::detect and the grid, the same
 * corners (FeaturesOrb.CornersAreOpenCvOrbsWithAnglesWhereDescribed). */
void BM_StageOrbCorners(benchmark::State& st, bool viaOpenCvOrb)
{
	const auto& d = data();
	features::TStereoFeatureOptions o;
	o.descriptor = features::DescriptorKind::Orb;
	o.orb_levels = 3;
	o.orb_scale_factor = 1.4;
	o.fast_threshold = 5;
	const features::CornerDescriber cd(o);
	auto detect = [&](const cv::Mat& img, int perCell, int border, features::CornerUse use, std::vector<cv::KeyPoint>& out) {
		if (!viaOpenCvOrb) return cd.detect(img, perCell, border, out, use);
		std::vector<cv::KeyPoint> all;
		cv::ORB::create(
			4 * o.grid_cols * o.grid_rows * perCell, static_cast<float>(o.orb_scale_factor), o.orb_levels,
			std::max(border, 3), 0, 2, cv::ORB::FAST_SCORE, features::kOrbPatchSize, o.fast_threshold)
			->detect(img, all);
		features::spreadOverGrid(all, img.cols, img.rows, o.grid_cols, o.grid_rows, perCell, border, out);
	};
	std::vector<cv::KeyPoint> kl, kr;
	size_t i = 0;
	for (auto _ : st)
	{
		const size_t k = i++ % d.invL.size();
		detect(d.invL[k], o.max_per_cell, cd.border(), features::CornerUse::Described, kl);
		detect(d.invR[k], o.max_per_cell_right, o.patch_radius + 3, features::CornerUse::Candidates, kr);
	}
	st.counters["left"] = static_cast<double>(kl.size());
	st.counters["right"] = static_cast<double>(kr.size());
}
BENCHMARK_CAPTURE(BM_StageOrbCorners, corner_describer, false)->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_StageOrbCorners, opencv_orb, true)->Unit(benchmark::kMicrosecond);

void BM_StageStereoMeasurements(benchmark::State& st)
{
	const auto& d = data();
	features::StereoFeatureExtractor ex;
	features::TStereoFrame fr;
	for (auto _ : st) ex.process(d.monoL[0], d.monoR[0], d.calib, fr);
	st.counters["measurements"] = static_cast<double>(fr.meas.size());
	st.counters["ms_detect"] = fr.timings.detect_ms;
	st.counters["ms_stereo"] = fr.timings.stereo_ms;
	st.counters["ms_describe"] = fr.timings.describe_ms;
}
BENCHMARK(BM_StageStereoMeasurements)->Unit(benchmark::kMicrosecond);

/** The keyframe matcher and the relative-pose estimator alone: frame 0 is
 * the keyframe, frame 1 the current frame, the prediction the VO's pose. */
struct TStageInputs
{
	features::TStereoFrame kf, cur;
	Eigen::Isometry3d T_curr_kf = Eigen::Isometry3d::Identity();
};
const TStageInputs& stageInputs()
{
	static const TStageInputs s = [] {
		const auto& d = data();
		TStageInputs s;
		features::StereoFeatureExtractor ex;
		ex.process(d.monoL[0], d.monoR[0], d.calib, s.kf);
		ex.process(d.monoL[1], d.monoR[1], d.calib, s.cur);
		vo::StereoVO v;
		v.setMinLoggingLevel(mrpt::system::LVL_ERROR);
		v.process(d.monoL[0], d.monoR[0], d.calib, 0.0);
		s.T_curr_kf = v.process(d.monoL[1], d.monoR[1], d.calib, 0.1).T_kf_curr.inverse();
		return s;
	}();
	return s;
}
vo::TKeyframeMatchInput matchInput(const TStageInputs& s)
{
	vo::TKeyframeMatchInput in;
	in.landmarks = &s.kf.meas;
	in.calib_kf = data().calib;
	in.frame = &s.cur;
	in.calib = data().calib;
	in.T_curr_kf_pred = s.T_curr_kf;
	// For the gate: a prediction uncertain by 5 cm and 0.5 deg (1 sigma).
	in.cov_T_curr_kf_pred.diagonal() << 25e-4, 25e-4, 25e-4, 7.6e-5, 7.6e-5, 7.6e-5;
	return in;
}

void BM_StageKeyframeMatcher(benchmark::State& st, vo::SearchRegion region)
{
	const auto& s = stageInputs();
	auto o = vo::matcherOptionsFrom(vo::TStereoVOOptions());
	o.region = region;
	const vo::KeyframeMatcher m(o);
	const auto in = matchInput(s);
	vo::TKeyframeMatchOutput out;
	for (auto _ : st) m.match(in, out);
	st.counters["landmarks"] = static_cast<double>(s.kf.meas.size());
	st.counters["correspondences"] = static_cast<double>(out.corr.size());
}
BENCHMARK_CAPTURE(BM_StageKeyframeMatcher, circle, vo::SearchRegion::Circle)->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_StageKeyframeMatcher, gate, vo::SearchRegion::Gate)->Unit(benchmark::kMicrosecond);

void BM_StageRelativePoseEstimator(benchmark::State& st, bool withPrior)
{
	const auto& s = stageInputs();
	vo::TKeyframeMatchOutput mo;
	vo::KeyframeMatcher(vo::matcherOptionsFrom(vo::TStereoVOOptions())).match(matchInput(s), mo);
	const vo::RelativePoseEstimator est(vo::poseEstimatorOptionsFrom(vo::TStereoVOOptions()));
	vo::TRelativePoseInput in;
	in.corr = &mo.corr;
	in.calib = data().calib;
	in.T_curr_ref_pred = withPrior ? &s.T_curr_kf : nullptr;
	vo::TRelativePoseOutput out;
	for (auto _ : st) est.estimate(in, out);
	st.counters["correspondences"] = static_cast<double>(mo.corr.size());
	st.counters["inliers"] = static_cast<double>(out.inliers);
	st.counters["ms_relpose_ransac"] = out.ms_ransac;
	st.counters["ms_relpose_solve"] = out.ms_solve;
}
BENCHMARK_CAPTURE(BM_StageRelativePoseEstimator, with_prior, true)->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_StageRelativePoseEstimator, without_prior, false)->Unit(benchmark::kMicrosecond);

void BM_ChannelConversionPair(benchmark::State& st, bool invariant)
{
	const auto& d = data();
	const auto c = filters::defaultChannel(invariant ? "invariant" : "mono");
	cv::Mat a, b;
	for (auto _ : st)
	{
		c.convert(d.colourL[0], a);
		c.convert(d.colourR[0], b);
	}
}
BENCHMARK_CAPTURE(BM_ChannelConversionPair, mono, false)->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_ChannelConversionPair, invariant, true)->Unit(benchmark::kMicrosecond);
}  // namespace

int main(int argc, char** argv)
{
	// One thread per channel pipeline: OpenCV's own worker pool would make
	// one channel compete with the other for the same two cores.
	cv::setNumThreads(1);
	benchmark::Initialize(&argc, argv);
	if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
	benchmark::RunSpecifiedBenchmarks();
	benchmark::Shutdown();
	return 0;
}
