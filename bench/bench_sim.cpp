/* Simulator speed: stereo frames per second at 512x384 (both eyes, shadow
 * rays, exposure, noise, 8-bit) in each stretch of the route and lighting,
 * and the cost of turning a frame into a rawlog record. */
#include <shadyloc/io/Rawlog.h>
#include <shadyloc/sim/StereoSimulator.h>

#include <benchmark/benchmark.h>

#include <filesystem>

using namespace shadyloc::sim;

namespace
{
std::string configPath()
{
	// bench binaries are built in build/bench; the config is in the source tree.
	for (const char* p : {"config/sim.ini", "../config/sim.ini", "../../config/sim.ini"})
		if (std::filesystem::exists(p)) return p;
	return std::string(SHADYLOC_SHARED_DATA_DIR) + "/../../wt-sim/config/sim.ini";
}

/** Renders consecutive frames of `traversal` starting at route position s0. */
void renderAt(benchmark::State& state, const char* traversal, double s0)
{
	auto o = TSimOptions::FromFile(configPath());
	StereoSimulator sim(o);
	auto t = o.traversal(traversal);
	t.start_s_m = s0;
	sim.setTraversal(t);
	int i = 0;
	for (auto _ : state)
	{
		TSimFrame f = sim.renderFrame(i++ % 50);
		benchmark::DoNotOptimize(f.left.data);
	}
	state.counters["frames/s"] = benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
	state.SetLabel(std::to_string(o.camera.width) + "x" + std::to_string(o.camera.height) + " stereo");
}
}  // namespace

static void BM_SimTrees_Noon(benchmark::State& s) { renderAt(s, "noon", 20); }
static void BM_SimTrees_LowSun(benchmark::State& s) { renderAt(s, "morning_low_sun", 20); }
static void BM_SimBuildings_Noon(benchmark::State& s) { renderAt(s, "noon", 140); }
static void BM_SimOpen_Evening(benchmark::State& s) { renderAt(s, "evening_warm", 230); }
static void BM_SimTrees_Overcast(benchmark::State& s) { renderAt(s, "overcast", 20); }
BENCHMARK(BM_SimTrees_Noon)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_SimTrees_LowSun)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_SimBuildings_Noon)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_SimOpen_Evening)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_SimTrees_Overcast)->Unit(benchmark::kMillisecond)->UseRealTime();

/** Frame -> observation -> gzip rawlog record (what `shadyloc sim` adds). */
static void BM_SimWriteRawlog(benchmark::State& state)
{
	auto o = TSimOptions::FromFile(configPath());
	StereoSimulator sim(o);
	const TSimFrame f = sim.renderFrame(0);
	const std::string path = (std::filesystem::temp_directory_path() / "bench_sim.rawlog").string();
	{
		shadyloc::io::RawlogWriter w(path);
		for (auto _ : state) w.write(*sim.makeObservation(f));
	}  // not committed: the temporary file is removed
	state.counters["frames/s"] = benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_SimWriteRawlog)->Unit(benchmark::kMillisecond)->UseRealTime();

BENCHMARK_MAIN();
