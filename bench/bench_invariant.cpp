/* Benchmark of the per-pixel colour transforms (issue: foundation, must-show 4).
 * Compares, in one run: the invariant table path, a naive per-pixel std::log
 * path, and OpenCV's cvtColor to grey (the floor of a per-pixel pass); and a
 * stereo pair on one thread vs two. Prints Mpix/s and the ratios at the end.
 *   build/bench/bench_invariant [--benchmark_min_time=0.5] */
#include <shadyloc/image/ColourTransforms.h>

#include <benchmark/benchmark.h>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <filesystem>
#include <iostream>
#include <map>

using namespace shadyloc::image;

namespace
{
// A real outdoor image when ../shared/data is there (more honest branch and
// cache behaviour than noise), else a synthetic one of the Bumblebee2 size.
const cv::Mat& testImage()
{
	static cv::Mat img = [] {
		const std::string p = std::string(SHADYLOC_SHARED_DATA_DIR) + "/shadow-pairs/p2_shadow1.jpg";
		cv::Mat m = std::filesystem::exists(p) ? cv::imread(p) : cv::Mat();
		if (m.empty())
		{
			m.create(384, 512, CV_8UC3);
			cv::randu(m, 0, 255);
			cv::GaussianBlur(m, m, cv::Size(5, 5), 1.5);
		}
		return m;
	}();
	return img;
}

InvariantParams params()
{
	auto p = InvariantParams::FromAlphaBeta(0.48, 0.5065);
	p.linearisation = Linearisation::SRGB;
	return p;
}

void setRate(benchmark::State& st, double pixelsPerIteration)
{
	st.counters["Mpix/s"] = benchmark::Counter(
		pixelsPerIteration * double(st.iterations()) / 1e6, benchmark::Counter::kIsRate);
}

void BM_InvariantTable(benchmark::State& st)
{
	const InvariantTransform t(params());
	cv::Mat out;
	for (auto _ : st)
	{
		t.apply(testImage(), out);
		benchmark::DoNotOptimize(out.data);
	}
	setRate(st, double(testImage().total()));
}
// The same with compressed tails (the 8-bit mapping calibrate-alpha fits to
// the UIUC pairs: 1.6 % of pixels beyond the knees): the cost of the tone table.
void BM_InvariantTableCompressedTails(benchmark::State& st)
{
	auto p = params();
	p.scale = 171.37;
	p.offset = 0.799;
	p.knee_low = 34.06;
	p.knee_high = 244.06;
	p.tail_slope_low = p.tail_slope_high = 0.2745;
	const InvariantTransform t(p);
	cv::Mat out;
	for (auto _ : st)
	{
		t.apply(testImage(), out);
		benchmark::DoNotOptimize(out.data);
	}
	setRate(st, double(testImage().total()));
}
void BM_InvariantNaiveLog(benchmark::State& st)
{
	const auto p = params();
	cv::Mat out;
	for (auto _ : st)
	{
		invariantNaive8(testImage(), out, p);
		benchmark::DoNotOptimize(out.data);
	}
	setRate(st, double(testImage().total()));
}
void BM_CvtColorGrey(benchmark::State& st)
{
	cv::Mat out;
	for (auto _ : st)
	{
		cv::cvtColor(testImage(), out, cv::COLOR_BGR2GRAY);
		benchmark::DoNotOptimize(out.data);
	}
	setRate(st, double(testImage().total()));
}
void BM_InvariantStereoPair(benchmark::State& st)
{
	const InvariantTransform t(params());
	const cv::Mat right = testImage().clone();
	const bool parallel = st.range(0) != 0;
	cv::Mat a, b;
	for (auto _ : st)
	{
		t.applyPair(testImage(), right, a, b, parallel);
		benchmark::DoNotOptimize(a.data);
	}
	setRate(st, 2.0 * double(testImage().total()));
}
BENCHMARK(BM_InvariantTable)->Unit(benchmark::kMicrosecond)->UseRealTime();
BENCHMARK(BM_InvariantTableCompressedTails)->Unit(benchmark::kMicrosecond)->UseRealTime();
BENCHMARK(BM_InvariantNaiveLog)->Unit(benchmark::kMicrosecond)->UseRealTime();
BENCHMARK(BM_CvtColorGrey)->Unit(benchmark::kMicrosecond)->UseRealTime();
BENCHMARK(BM_InvariantStereoPair)->Arg(0)->Arg(1)->ArgName("parallel")->Unit(benchmark::kMicrosecond)->UseRealTime();

// Console output plus the ratios the goals are stated in.
class RatioReporter : public benchmark::ConsoleReporter
{
   public:
	void ReportRuns(const std::vector<Run>& runs) override
	{
		for (const auto& r : runs)
			if (r.run_type == Run::RT_Iteration && !r.error_occurred)
				m_seconds[r.run_name.str()] = r.GetAdjustedRealTime();
		ConsoleReporter::ReportRuns(runs);
	}
	void Finalize() override
	{
		ConsoleReporter::Finalize();
		auto t = [&](const char* n) { return m_seconds.count(n) ? m_seconds[n] : 0.0; };
		const double table = t("BM_InvariantTable/real_time"), naive = t("BM_InvariantNaiveLog/real_time"),
					 grey = t("BM_CvtColorGrey/real_time"), tails = t("BM_InvariantTableCompressedTails/real_time"),
					 seq = t("BM_InvariantStereoPair/parallel:0/real_time"),
					 par = t("BM_InvariantStereoPair/parallel:1/real_time");
		std::cout << "\nimage: " << testImage().cols << "x" << testImage().rows << "\n";
		if (table > 0 && naive > 0)
			std::cout << "table path speed-up over naive std::log: " << naive / table << "x (goal >= 5)\n";
		if (table > 0 && grey > 0)
			std::cout << "table path time / cvtColor grey time:   " << table / grey << " (goal <= 3)\n";
		if (table > 0 && tails > 0)
			std::cout << "compressed tails / linear mapping time:  " << tails / table << "\n";
		if (seq > 0 && par > 0)
			std::cout << "stereo pair, two threads vs one:         " << seq / par << "x faster\n";
	}

   private:
	std::map<std::string, double> m_seconds;
};
}  // namespace

int main(int argc, char** argv)
{
	// One thread for OpenCV too, so that cvtColor is compared like with like
	// (it would otherwise split large images over every core).
	cv::setNumThreads(1);
	benchmark::Initialize(&argc, argv);
	RatioReporter reporter;
	benchmark::RunSpecifiedBenchmarks(&reporter);
	benchmark::Shutdown();
	return 0;
}
