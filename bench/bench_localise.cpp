/* ShadyLoc — speed of the combined localisation system per frame at 512x384
 * on the default dataset (docs/localisation.md, "Speed"): the noon map, the
 * overcast traversal live, frames decoded beforehand (decoding excluded).
 * BM_CombinedFrame: LocalisationSystem::processFrame (both channels'
 * conversion and features, live VO, both localisers, global search when the
 * place is unknown, policy) with [localise] threads = 2 and 1;
 * BM_VOFrameMono: the monochrome channel's conversion and the stereo VO alone
 * on the same frames, for the ratio. Each iteration is one frame, the run
 * played in order and restarted (as a new run, from the global search) at its
 * end. Counters: median and 95th percentile per frame [ms], from the frames
 * timed one by one; each localiser's stages (mean per frame) and each
 * channel's front end alone (BM_ChannelFrontEnd). Goals (issue #20):
 * combined median >= 60 Hz, 95th percentile >= 40 Hz, and the combined
 * median at most twice the VO's, both from one run.
 *
 * Needs rawlogs/generated (scripts/make-default-dataset.sh) and the built
 * `shadyloc` (the map is surveyed once into $TMPDIR/shadyloc_bench_localise);
 * skipped with a message otherwise. SHADYLOC_BENCH_VO_CONFIG=other.ini
 * stands for config/vo_sim.ini in the survey and the live system alike (e.g.
 * other [features]: FAST + BRIEF against ORB, docs/localisation.md).
 *   build/bench/bench_localise
 *   SHADYLOC_BENCH_VO_CONFIG=vo_sim_orb.ini build/bench/bench_localise */
#include <shadyloc/filters/Channel.h>
#include <shadyloc/io/StereoFrameSource.h>
#include <shadyloc/localisation/LocalisationSystem.h>
#include <shadyloc/vo/StereoVO.h>
#include <shadyloc/vo/ChannelOptions.h>

#include <mrpt/config/CConfigFileMemory.h>

#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

using namespace shadyloc;
namespace fs = std::filesystem;

namespace
{
using Clock = std::chrono::steady_clock;

std::string slurp(const std::string& p)
{
	std::ifstream f(p);
	std::ostringstream s;
	s << f.rdbuf();
	return s.str();
}

struct TData
{
	std::string skip;  //!< why the data is missing ("" when present)
	std::vector<io::TStereoFrame> frames;
	CKeyframeMap::Ptr map;
	std::string cfgText;
};

const TData& data()
{
	static const TData d = [] {
		TData d;
		const std::string src = SHADYLOC_SOURCE_DIR, gen = src + "/rawlogs/generated";
		for (const char* f : {"noon.rawlog", "noon.tum", "overcast.rawlog"})
			if (!fs::exists(gen + "/" + f))
			{
				d.skip = gen + "/" + f + " is absent: make it with scripts/make-default-dataset.sh";
				return d;
			}
		if (!fs::exists(SHADYLOC_APP))
		{
			d.skip = std::string("'") + SHADYLOC_APP + "' is absent: build shadyloc_app (it surveys the map)";
			return d;
		}
		const char* tmp = std::getenv("TMPDIR");
		const fs::path dir = fs::path(tmp ? tmp : "/tmp") / "shadyloc_bench_localise";
		fs::create_directories(dir);
		const char* voEnv = std::getenv("SHADYLOC_BENCH_VO_CONFIG");
		const std::string voCfg = voEnv && *voEnv ? voEnv : src + "/config/vo_sim.ini";
		if (!fs::is_regular_file(voCfg))
		{
			d.skip = "VO config '" + voCfg + "' (SHADYLOC_BENCH_VO_CONFIG) does not exist";
			return d;
		}
		// One map per VO config: the survey must make what the live run expects.
		const std::string mapPath = (dir / ("noon_" + fs::path(voCfg).stem().string() + ".kfmap")).string();
		const std::string cmd = std::string("'") + SHADYLOC_APP + "' survey -q -i '" + gen + "/noon.rawlog' -o '" + mapPath +
								"' -c '" + voCfg + "' --gt '" + gen + "/noon.tum' > /dev/null";
		if (std::system(cmd.c_str()) != 0)
		{
			d.skip = "the survey failed: " + cmd;
			return d;
		}
		d.map = CKeyframeMap::LoadFromFile(mapPath);
		d.cfgText = slurp(voCfg) + "\n" + slurp(src + "/config/localise_sim.ini");
		io::TStereoFrameSourceOptions so;
		so.sensorLabel = io::findStereoLabel(gen + "/overcast.rawlog", io::labelWithoutSuffixes({"_mono", "_inv", "_lin"}));
		io::StereoFrameSource source(gen + "/overcast.rawlog", so);
		io::TStereoFrame f;
		while (source.next(f))
		{
			f.obs.reset();	// the images are kept in left/right
			d.frames.push_back(f);
		}
		return d;
	}();
	return d;
}

double percentile(std::vector<double> v, double p)
{
	if (v.empty()) return 0;
	std::sort(v.begin(), v.end());
	return v[static_cast<size_t>(std::round(p * static_cast<double>(v.size() - 1)))];
}

void setCounters(benchmark::State& st, const std::vector<double>& ms, const std::string& prefix)
{
	st.counters[prefix + "median_ms"] = percentile(ms, 0.5);
	st.counters[prefix + "p95_ms"] = percentile(ms, 0.95);
}

/** The combined system, one frame per iteration; `extra` config lines
 * override the shipped ones (a later key wins). */
void BM_CombinedFrame(benchmark::State& st, int threads, const char* extra = "")
{
	const auto& d = data();
	if (!d.skip.empty())
	{
		st.SkipWithError(d.skip.c_str());
		return;
	}
	mrpt::config::CConfigFileMemory cfg(d.cfgText + "\n" + extra);
	auto sys = localisation::LocalisationSystem::FromConfig(cfg, d.map, {}, threads, "vo_sim.ini + localise_sim.ini");
	std::vector<double> ms, voMs;
	std::map<std::string, std::vector<double>> localiserMs;	 // each stage's and localiser's own time, by label
	std::map<std::string, std::map<std::string, double>> stageMs;  // inside each localiser: summed over the frames
	size_t i = 0, fixes = 0;
	for (auto _ : st)
	{
		if (i == d.frames.size())
		{
			sys->reset();  // a new run: it starts by the global search again
			i = 0;
		}
		const auto& f = d.frames[i++];
		const auto t0 = Clock::now();
		const auto u = sys->processFrame(f.left, f.right, f.calib, f.timestamp);
		const double t = std::chrono::duration<double>(Clock::now() - t0).count();
		st.SetIterationTime(t);
		ms.push_back(1e3 * t);
		voMs.push_back(u.vo.ms.total);
		for (const auto& r : u.localisers)
		{
			localiserMs[r.channel].push_back(r.ms);
			auto& m = stageMs[r.channel];
			m["search"] += r.ms_stage.search;
			m["solve"] += r.ms_stage.solve;
			m["patch_search"] += r.ms_stage.patch_search;
			m["patch_solve"] += r.ms_stage.patch_solve;
			m["covariance"] += r.ms_stage.covariance;
		}
		localiserMs["front_end"].push_back(u.ms_front_end);
		localiserMs["convert"].push_back(u.ms_convert);
		localiserMs["relocalise"].push_back(u.ms_relocalise);
		localiserMs["wait"].push_back(u.ms_wait);
		fixes += u.localised();
	}
	setCounters(st, ms, "");
	// The live VO's share inside the system (on the shared measurements).
	setCounters(st, voMs, "vo_inside_");
	// Where the frame's time goes: with 2 threads the channel localisers overlap, the joint one runs after both
	// (0 ms on the frames it is not run).
	for (const auto& [label, v] : localiserMs) setCounters(st, v, label + "_");
	// Inside each localiser, the mean per frame (a stage that does not run on a frame adds 0).
	for (const auto& [label, m] : stageMs)
	{
		double all = 0;
		for (const auto& kv : m) all += kv.second;
		if (all <= 0) continue;	 // a localiser without these stages (the joint one)
		for (const auto& [stage, sum] : m)
			st.counters[label + "_" + stage + "_mean_ms"] = sum / static_cast<double>(ms.size());
	}
	st.counters["fix_share"] = ms.empty() ? 0.0 : static_cast<double>(fixes) / static_cast<double>(ms.size());
}
/** Every CombinedFrame variant: one frame per iteration, timed by the
 * frame itself, 600 frames (several runs of the live traversal). */
void framesOfRuns(benchmark::internal::Benchmark* b)
{
	b->Unit(benchmark::kMillisecond)->UseManualTime()->Iterations(600);
}
BENCHMARK_CAPTURE(BM_CombinedFrame, threads2, 2)->Apply(framesOfRuns);
BENCHMARK_CAPTURE(BM_CombinedFrame, threads1, 1)->Apply(framesOfRuns);
// Without the fallback VO: its cost is the difference.
BENCHMARK_CAPTURE(BM_CombinedFrame, threads2_no_fallback_vo, 2, "[localise]\nvo_fallback_channel =\n")->Apply(framesOfRuns);
// With and without the joint localiser (JointLocaliser.h): its cost is the difference.
BENCHMARK_CAPTURE(BM_CombinedFrame, threads2_joint, 2, "[localise]\njoint = mono invariant\n")->Apply(framesOfRuns);
BENCHMARK_CAPTURE(BM_CombinedFrame, threads2_no_joint, 2, "[localise]\njoint =\n")->Apply(framesOfRuns);
// The joint solve on every frame, not only where one of its channels has no accepted fix.
BENCHMARK_CAPTURE(BM_CombinedFrame, threads2_joint_every_frame, 2, "[localise]\njoint_only_where_a_channel_fails = false\n")
	->Apply(framesOfRuns);
// The patch pass after every solve, as before the twenty-third session
// (shipped: only where the descriptor solve keeps fewer than 60 inliers, 40
// for the monochrome one; docs/localisation.md, "Where the patch pass runs").
BENCHMARK_CAPTURE(
	BM_CombinedFrame, threads2_patch_pass_always, 2,
	"[localiser]\npatch_search_max_inliers = 0\n[localiser.mono]\npatch_search_max_inliers = 0\n")
	->Apply(framesOfRuns);
// The monochrome localiser's patch pass bounded as the invariant one's (60 inliers, the twenty-third session's).
BENCHMARK_CAPTURE(BM_CombinedFrame, threads2_mono_patch_bound_60, 2, "[localiser.mono]\npatch_search_max_inliers = 60\n")
	->Apply(framesOfRuns);
// The bootstrap's resamples each re-linearised, as before the twenty-sixth
// session (shipped: the chord method, the solve's Jacobians kept).
BENCHMARK_CAPTURE(
	BM_CombinedFrame, threads2_bootstrap_relinearised, 2, "[localiser]\nbootstrap_relinearise = true\n")
	->Apply(framesOfRuns);
// Without the patch pass and the warped patches (docs/localisation.md,
// "Patches that follow the viewpoint"): their cost is the difference.
BENCHMARK_CAPTURE(BM_CombinedFrame, threads2_no_patch_pass, 2, "[localiser]\npatch_search = false\nwarp_patches = false\n")
	->Apply(framesOfRuns);

/** The search of the whole map for the place of one live frame (a lost run:
 * LocalisationSystem searches so after global_search_after_frames without a
 * fix), per channel: frame 60 of the live run, measured by the system's own
 * front end. Counters: the map's keyframes and the channel's landmarks, and
 * the time per keyframe, which is what grows with a map of several
 * experiences. */
void BM_WholeMapSearch(benchmark::State& st, const char* channel, const char* extra = "")
{
	const auto& d = data();
	if (!d.skip.empty())
	{
		st.SkipWithError(d.skip.c_str());
		return;
	}
	mrpt::config::CConfigFileMemory cfg(d.cfgText + "\n" + extra);
	auto sys = localisation::LocalisationSystem::FromConfig(cfg, d.map, {}, 1, "vo_sim.ini + localise_sim.ini");
	const auto labels = sys->channelLabels();
	const size_t c = static_cast<size_t>(std::find(labels.begin(), labels.end(), channel) - labels.begin());
	const auto* L = sys->localiser(channel);
	if (c == labels.size() || !L)
	{
		st.SkipWithError("no such channel localiser");
		return;
	}
	features::TStereoFrame meas;
	sys->setFrameHook([&](auto&, const auto& m, const auto&) { meas = m[c]; });
	for (size_t i = 0; i <= 60 && i < d.frames.size(); i++)
		sys->processFrame(d.frames[i].left, d.frames[i].right, d.frames[i].calib, d.frames[i].timestamp);
	const auto& calib = d.frames.front().calib;
	size_t found = 0, runs = 0;
	double seconds = 0;
	for (auto _ : st)
	{
		const auto t0 = Clock::now();
		found += L->globalSearch(meas, calib, 17).ok;
		seconds += std::chrono::duration<double>(Clock::now() - t0).count();
		runs++;
	}
	size_t landmarks = 0;
	for (uint32_t k = 0; k < d.map->keyframeCount(); k++) landmarks += d.map->measurements(k, channel).size();
	st.counters["keyframes"] = static_cast<double>(d.map->keyframeCount());
	st.counters["landmarks"] = static_cast<double>(landmarks);
	st.counters["live_features"] = static_cast<double>(meas.meas.size());
	st.counters["found_share"] = runs ? static_cast<double>(found) / static_cast<double>(runs) : 0.0;
	st.counters["ms_per_keyframe"] =
		runs ? 1e3 * seconds / static_cast<double>(runs) / static_cast<double>(d.map->keyframeCount()) : 0.0;
}
BENCHMARK_CAPTURE(BM_WholeMapSearch, mono, "mono")->Unit(benchmark::kMillisecond)->Iterations(20);
BENCHMARK_CAPTURE(BM_WholeMapSearch, invariant, "invariant")->Unit(benchmark::kMillisecond)->Iterations(20);
// The monochrome search as it was before its votes only ranked (floor 15,
// the invariant channel's): what checking every ranked candidate costs.
BENCHMARK_CAPTURE(BM_WholeMapSearch, mono_min_votes_15, "mono", "[localiser.mono]\nglobal_min_votes = 15\n")
	->Unit(benchmark::kMillisecond)
	->Iterations(20);

/** The monochrome channel's conversion and the stereo VO alone, on the same frames. */
void BM_VOFrameMono(benchmark::State& st)
{
	const auto& d = data();
	if (!d.skip.empty())
	{
		st.SkipWithError(d.skip.c_str());
		return;
	}
	mrpt::config::CConfigFileMemory cfg(d.cfgText);
	const auto ch = filters::channelFromConfig(cfg, "mono", "vo_sim.ini");
	vo::StereoVO vo(vo::voOptionsFor(cfg, ch.label), vo::featureOptionsFor(cfg, ch.label));
	vo.setMinLoggingLevel(mrpt::system::LVL_ERROR);
	std::vector<double> ms, trackMs;
	size_t i = 0;
	for (auto _ : st)
	{
		if (i == d.frames.size())
		{
			vo.reset();
			i = 0;
		}
		const auto& f = d.frames[i++];
		const auto t0 = Clock::now();
		cv::Mat l, r;
		ch.convertPair(f.left, f.right, l, r);
		const auto res = vo.process(l, r, f.calib, f.timestamp);
		const double t = std::chrono::duration<double>(Clock::now() - t0).count();
		st.SetIterationTime(t);
		ms.push_back(1e3 * t);
		// The VO after its features: what the combined system's vo_inside_ counters time.
		trackMs.push_back(res.ms.total - res.ms.detect - res.ms.stereo - res.ms.describe);
	}
	setCounters(st, ms, "");
	setCounters(st, trackMs, "after_features_");
}
BENCHMARK(BM_VOFrameMono)->Unit(benchmark::kMillisecond)->UseManualTime()->Iterations(600);

/** One channel's front end alone on the same frames (conversion, then the
 * stereo features): where its time goes, by stage. */
void BM_ChannelFrontEnd(benchmark::State& st, const char* channel, const char* extra = "")
{
	const auto& d = data();
	if (!d.skip.empty())
	{
		st.SkipWithError(d.skip.c_str());
		return;
	}
	mrpt::config::CConfigFileMemory cfg(d.cfgText + "\n" + extra);
	const auto ch = filters::channelFromConfig(cfg, channel, "vo_sim.ini");
	const features::StereoFeatureExtractor fx(vo::featureOptionsFor(cfg, ch.label));
	std::vector<double> ms, convert, detect, stereo, describe, kept;
	size_t i = 0;
	for (auto _ : st)
	{
		const auto& f = d.frames[i++ % d.frames.size()];
		const auto t0 = Clock::now();
		cv::Mat l, r;
		ch.convertPair(f.left, f.right, l, r);
		const double tc = std::chrono::duration<double>(Clock::now() - t0).count();
		features::TStereoFrame out;
		fx.process(l, r, f.calib, out);
		const double t = std::chrono::duration<double>(Clock::now() - t0).count();
		st.SetIterationTime(t);
		ms.push_back(1e3 * t);
		convert.push_back(1e3 * tc);
		detect.push_back(out.timings.detect_ms);
		stereo.push_back(out.timings.stereo_ms);
		describe.push_back(out.timings.describe_ms);
		kept.push_back(static_cast<double>(out.meas.size()));
	}
	setCounters(st, ms, "");
	setCounters(st, convert, "convert_");
	setCounters(st, detect, "detect_");
	setCounters(st, stereo, "stereo_");
	setCounters(st, describe, "describe_");
	st.counters["measurements"] = percentile(kept, 0.5);
}
BENCHMARK_CAPTURE(BM_ChannelFrontEnd, mono, "mono")->Unit(benchmark::kMillisecond)->UseManualTime()->Iterations(300);
BENCHMARK_CAPTURE(BM_ChannelFrontEnd, invariant, "invariant")
	->Unit(benchmark::kMillisecond)
	->UseManualTime()
	->Iterations(300);
BENCHMARK_CAPTURE(BM_ChannelFrontEnd, invariant_right_levels_2, "invariant", "[features.invariant]\norb_right_levels = 2\n")
	->Unit(benchmark::kMillisecond)
	->UseManualTime()
	->Iterations(300);

}  // namespace

BENCHMARK_MAIN();
