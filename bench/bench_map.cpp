/* Keyframe map queries on a 100 km map: 150,000 synthetic keyframe poses
 * (0.67 m apart) along a winding road that crosses itself and is driven both
 * ways. Measures the nearest-keyframe query (hash grid, heading filter), the
 * along-chain query and the relative pose with covariance over 10 keyframes.
 *   build/bench/bench_map */
#include <shadyloc/map/CKeyframeMap.h>

#include <benchmark/benchmark.h>

#include <random>

using namespace shadyloc;

namespace
{
constexpr int kKeyframes = 150000;
constexpr double kSpacing = 100000.0 / kKeyframes;	// [m]

/** Poses only (no measurements): the queries touch poses and the index. */
const CKeyframeMap& bigMap()
{
	static CKeyframeMap::Ptr m = [] {
		auto map = CKeyframeMap::Create();
		geometry::TStereoCalib cal;
		map::TChannelParams a, b;
		a.label = "mono";
		a.filter_class = "shadyloc::CFilterMonochrome";
		b.label = "invariant";
		b.filter_class = "shadyloc::CFilterInvariant";
		map->setup(cal, 512, 384, {a, b});
		const uint16_t run = map->addRun("synthetic-100km");
		std::mt19937 rng(5);
		std::normal_distribution<double> N(0, 1);
		double yaw = 0, yawRate = 0;
		Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
		for (int i = 0; i < kKeyframes; i++)
		{
			map::TMapKeyframe k;
			k.run = run;
			k.frame = i;
			k.timestamp = 0.1 * i;
			Eigen::Isometry3d step = Eigen::Isometry3d::Identity();
			if (i > 0)
			{
				// A road of curves: yaw rate as a slow random walk, kept within
				// +-0.01 rad/m, so the road winds over a ~10 km wide area.
				yawRate = std::clamp(yawRate + 2e-4 * N(rng), -0.01, 0.01);
				yaw = yawRate * kSpacing;
				step.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitY()).toRotationMatrix();
				step.translation() = Eigen::Vector3d(0, 0, kSpacing);
			}
			T = T * step;
			k.T_prev_kf = step;
			k.T_map_kf = T;
			k.cov_prev_kf = geometry::Matrix6d::Identity() * 1e-4;
			k.channels.resize(2);
			map->appendKeyframe(std::move(k));
		}
		return map;
	}();
	return *m;
}

/** Query poses near the map: a keyframe's pose, offset by up to 2 m and 20 deg. */
std::vector<Eigen::Isometry3d> queries(int n)
{
	const auto& m = bigMap();
	std::mt19937 rng(9);
	std::uniform_int_distribution<uint32_t> K(0, kKeyframes - 1);
	std::uniform_real_distribution<double> U(-1, 1);
	std::vector<Eigen::Isometry3d> q;
	for (int i = 0; i < n; i++)
	{
		Eigen::Isometry3d T = m.keyframe(K(rng)).T_map_kf;
		T.translation() += Eigen::Vector3d(2 * U(rng), 0.2 * U(rng), 2 * U(rng));
		T.linear() = T.linear() * Eigen::AngleAxisd(0.35 * U(rng), Eigen::Vector3d::UnitY()).toRotationMatrix();
		q.push_back(T);
	}
	return q;
}

void BM_NearestKeyframes(benchmark::State& st)
{
	const auto& m = bigMap();
	const auto qs = queries(1024);
	map::TNearestQuery q;
	q.max_distance_m = static_cast<double>(st.range(0));
	size_t i = 0, found = 0;
	for (auto _ : st)
	{
		const auto hits = m.nearestKeyframes(qs[i++ & 1023], q);
		found += hits.size();
		benchmark::DoNotOptimize(hits.data());
	}
	st.counters["hits/query"] = static_cast<double>(found) / st.iterations();
	st.counters["keyframes"] = kKeyframes;
}
BENCHMARK(BM_NearestKeyframes)->Arg(5)->Arg(20)->Unit(benchmark::kMicrosecond);

void BM_KeyframesAlongChain(benchmark::State& st)
{
	const auto& m = bigMap();
	std::mt19937 rng(1);
	std::uniform_int_distribution<uint32_t> K(0, kKeyframes - 1);
	for (auto _ : st)
	{
		const auto ids = m.keyframesAlongChain(K(rng), 5.0, 20.0);
		benchmark::DoNotOptimize(ids.data());
	}
}
BENCHMARK(BM_KeyframesAlongChain)->Unit(benchmark::kMicrosecond);

void BM_RelativePose10(benchmark::State& st)
{
	const auto& m = bigMap();
	std::mt19937 rng(2);
	std::uniform_int_distribution<uint32_t> K(0, kKeyframes - 11);
	for (auto _ : st)
	{
		const uint32_t a = K(rng);
		const auto r = m.relativePose(a, a + 10);
		benchmark::DoNotOptimize(r.cov.data());
	}
}
BENCHMARK(BM_RelativePose10)->Unit(benchmark::kMicrosecond);

void BM_BuildIndex150k(benchmark::State& st)
{
	// Appending 150,000 pose-only keyframes (quantisation, chain distance, index).
	const auto& src = bigMap();
	for (auto _ : st)
	{
		CKeyframeMap m;
		m.setup(src.calibration(), 512, 384, src.channels());
		m.addRun("copy");
		for (const auto& k : src.keyframes()) m.appendKeyframe(k);
		benchmark::DoNotOptimize(m.keyframeCount());
	}
}
BENCHMARK(BM_BuildIndex150k)->Unit(benchmark::kMillisecond)->Iterations(3);

}  // namespace

BENCHMARK_MAIN();
