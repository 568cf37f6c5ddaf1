/* Speed of the unsupervised alpha estimate (issue goal: 100 frames of 512x384
 * in under 5 s on one core). Frames: coloured cells with brightness texture
 * and sky-lit shadows, narrowband/Wien model, linear 8-bit. */
#include <shadyloc/image/InvariantCalibration.h>

#include <benchmark/benchmark.h>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <cmath>
#include <random>

using namespace shadyloc::image;

namespace
{
const std::vector<cv::Mat>& frames()
{
	static std::vector<cv::Mat> f = [] {
		std::vector<cv::Mat> out;
		const double L[3] = {450, 545, 610}, c2 = 1.4388e7;
		auto term = [&](int k, double T) { return std::pow(L[k], -5) * std::exp(-c2 / (T * L[k])); };
		std::mt19937 rng(3);
		std::uniform_real_distribution<double> u(0.08, 0.9);
		for (int i = 0; i < 100; i++)
		{
			cv::Mat shadow(384, 512, CV_8U, cv::Scalar(0));
			for (int k = 0; k < 4; k++)
				cv::circle(shadow, {int(u(rng) * 512), int(u(rng) * 384)}, 40 + 10 * k, cv::Scalar(255), cv::FILLED);
			std::vector<std::array<double, 3>> rho(18 * 14);
			for (auto& r : rho) r = {u(rng), u(rng), u(rng)};
			cv::Mat img(384, 512, CV_8UC3);
			for (int y = 0; y < 384; y++)
				for (int x = 0; x < 512; x++)
				{
					const bool sh = shadow.at<uint8_t>(y, x);
					const double T = sh ? 13000 : 5200, I0 = sh ? 0.18 : 1.0;
					const auto& r = rho[(y / 30) * 18 + x / 30];
					const double tex = 0.85 + 0.3 * ((x * 7 + y * 13) % 17) / 16.0;
					for (int k = 0; k < 3; k++)
						img.at<cv::Vec3b>(y, x)[k] = cv::saturate_cast<uint8_t>(
							255 * 0.7 * I0 * r[k] * tex * term(k, T) / term(1, T) * term(1, 6500) / term(k, 6500));
				}
			out.push_back(img);
		}
		return out;
	}();
	return f;
}

void BM_EdgeAlpha100Frames(benchmark::State& st)
{
	const auto& f = frames();
	TCalibrationInput in;
	TAlphaSearch s;
	s.bootstrapRounds = int(st.range(0));
	for (auto _ : st)
	{
		const auto c = alphaByEdgeDirections(edgeSamples(f, in), s);
		benchmark::DoNotOptimize(c.best);
	}
}
BENCHMARK(BM_EdgeAlpha100Frames)->Arg(0)->Arg(200)->Unit(benchmark::kMillisecond);

void BM_EntropyAlpha100Frames(benchmark::State& st)
{
	const auto& f = frames();
	TCalibrationInput in;
	TAlphaSearch s;
	s.bootstrapRounds = 0;
	// Arg 0: the default (quantiles from a fine histogram); 1: exact
	// quantiles by partial sorts, the former implementation, for the ratio.
	const auto q = st.range(0) == 0 ? EntropyQuantiles::Histogram : EntropyQuantiles::Sorted;
	for (auto _ : st)
	{
		const auto c = alphaByEntropy(chromaSamples(f, in), s, q);
		benchmark::DoNotOptimize(c.best);
	}
}
BENCHMARK(BM_EntropyAlpha100Frames)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

void BM_CalibrateMapping100Frames(benchmark::State& st)
{
	const auto& f = frames();
	TCalibrationInput in;
	for (auto _ : st)
	{
		const auto p = calibrateMapping(f, in.params(0.34));
		benchmark::DoNotOptimize(p.scale);
	}
}
BENCHMARK(BM_CalibrateMapping100Frames)->Unit(benchmark::kMillisecond);
}  // namespace

BENCHMARK_MAIN();
