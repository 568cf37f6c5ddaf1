/* ShadyLoc simulator — rendering, exposure, noise, rawlog output. */
#include <shadyloc/io/AtomicFile.h>
#include <shadyloc/io/OutputTransaction.h>
#include <shadyloc/io/Rawlog.h>
#include <shadyloc/io/Tum.h>
#include <shadyloc/sim/StereoSimulator.h>
#include <shadyloc/sim/Noise.h>

#include <mrpt/math/CMatrixFixed.h>
#include <mrpt/poses/CPose3DQuat.h>

#include <opencv2/core.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <future>
#include <iomanip>
#include <stdexcept>
#include <string>

namespace shadyloc::sim
{
namespace
{
constexpr double kSpeedPeriod_s = 20.0;	 // slow speed oscillation
constexpr double kWeavePeriod_s = 13.0;	 // slow lateral weave
}  // namespace

StereoSimulator::StereoSimulator(const TSimOptions& opts)
	: mrpt::system::COutputLogger("StereoSimulator"), m_opts(opts), m_scene(opts.scene)
{
	m_opts.camera.validate();
	if (!m_opts.traversals.empty())
		setTraversal(m_opts.traversals.front());
	else
	{
		TTraversal t;
		t.name = "default";
		setTraversal(t);
	}
}

void StereoSimulator::setTraversal(const TTraversal& t)
{
	t.validate();
	m_trav = t;
	const auto& cam = m_opts.camera;
	const auto& g = cam.grid;
	const auto sens = cam.spectral.sensitivities(g);
	const double eSun = t.effectiveSunIrradiance();
	m_sunOn = eSun > 0 ? 1.0f : 0.0f;
	Spectrum sun = planckian(g, t.sun_temperature_K), sky = planckian(g, t.sky_temperature_K);
	for (auto& v : sun) v *= eSun;
	for (auto& v : sky) v *= t.sky_irradiance;
	for (int m = 0; m < kMaterialCount; m++)
		for (int j = 0; j < 2; j++)
		{
			const Spectrum rho = materialReflectance(m, j).sample(g);
			const Rgb a = response(sens, sun, rho, g.step_nm), b = response(sens, sky, rho, g.step_nm);
			for (int k = 0; k < 3; k++)
			{
				m_respSun[m][j][k] = static_cast<float>(a[k]);
				m_respSky[m][j][k] = static_cast<float>(b[k]);
			}
		}
	const Spectrum white(g.size(), 1.0);
	const Rgb ws = response(sens, sun, white, g.step_nm), wk = response(sens, sky, white, g.step_nm);
	for (int k = 0; k < 3; k++)
	{
		m_sunWhite[k] = static_cast<float>(ws[k]);
		m_skyWhite[k] = static_cast<float>(wk[k]);
	}
	const double az = t.sun_azimuth_deg * M_PI / 180, el = t.sun_elevation_deg * M_PI / 180;
	m_sun = V3(static_cast<float>(std::sin(az) * std::cos(el)), static_cast<float>(std::cos(az) * std::cos(el)),
		static_cast<float>(std::sin(el)));
	m_wind = m_scene.windOffset(t.wind_seed);
	SplitMix64 rng(0x7a11ULL * (t.noise_seed + 1));
	m_phaseSpeed = rng.uniform(0, 2 * M_PI);
	m_phaseWeave = rng.uniform(0, 2 * M_PI);
	m_prevGain = 0;
}

// ------------------------------------------------------------------ geometry
mrpt::img::TCamera StereoSimulator::leftCamera() const
{
	const auto& c = m_opts.camera;
	mrpt::img::TCamera cam;
	cam.ncols = static_cast<uint32_t>(c.width);
	cam.nrows = static_cast<uint32_t>(c.height);
	cam.setIntrinsicParamsFromValues(c.focalPx(), c.focalPx(), c.cx(), c.cy());
	cam.dist.fill(0);  // rendered as an ideal pinhole: already rectified
	return cam;
}

mrpt::poses::CPose3D StereoSimulator::T_vehicle_left() const
{
	const double p = m_opts.camera.pitch_deg * M_PI / 180;
	// Columns: camera x (right), y (down), z (forward, tilted down by p) in
	// the vehicle frame (x forward, y left, z up).
	mrpt::math::CMatrixDouble33 R;
	const double zc[3] = {std::cos(p), 0, -std::sin(p)}, xc[3] = {0, -1, 0};
	const double yc[3] = {zc[1] * xc[2] - zc[2] * xc[1], zc[2] * xc[0] - zc[0] * xc[2], zc[0] * xc[1] - zc[1] * xc[0]};
	for (int r = 0; r < 3; r++)
	{
		R(r, 0) = xc[r];
		R(r, 1) = yc[r];
		R(r, 2) = zc[r];
	}
	mrpt::math::CVectorFixedDouble<3> t;
	t[0] = 0;
	t[1] = 0.5 * m_opts.camera.baseline_m;
	t[2] = m_opts.camera.height_m;
	return mrpt::poses::CPose3D(R, t);
}

mrpt::poses::CPose3D StereoSimulator::T_left_right() const
{
	return mrpt::poses::CPose3D(m_opts.camera.baseline_m, 0, 0, 0, 0, 0);
}

double StereoSimulator::timestamp(int frame) const { return m_trav.start_time + frame / m_opts.camera.fps; }

double StereoSimulator::routePosition(int frame) const
{
	// s(t) = s0 + v0 t + integral of v0 a sin(w t + phi): closed form.
	const double t = frame / m_opts.camera.fps, v0 = m_trav.speed_mps, a = m_trav.speed_variation;
	const double w = 2 * M_PI / kSpeedPeriod_s;
	return m_trav.start_s_m + v0 * t - v0 * a / w * (std::cos(w * t + m_phaseSpeed) - std::cos(m_phaseSpeed));
}

int StereoSimulator::frameCount() const
{
	if (!m_trav.endsByDistance()) return m_trav.frames;
	constexpr int kMaxFrames = 1000000;
	for (int i = 0; i < kMaxFrames; i++)
		if (routePosition(i) >= m_trav.end_s_m) return i + 1;
	throw std::invalid_argument(
		"[traversal." + m_trav.name + "] more than 1e6 frames from start_s_m to end_s_m at speed_mps = " +
		std::to_string(m_trav.speed_mps));
}

mrpt::poses::CPose3D StereoSimulator::T_world_vehicle(int frame) const
{
	const double t = frame / m_opts.camera.fps;
	const double s = routePosition(frame);
	const double w = 2 * M_PI / kWeavePeriod_s;
	const double lat = m_opts.scene.lane_offset_m + m_trav.lateral_offset_m +
					   m_trav.weave_amplitude_m * std::sin(w * t + m_phaseWeave);
	const double latRate = m_trav.weave_amplitude_m * w * std::cos(w * t + m_phaseWeave);
	const double v = m_trav.speed_mps * (1 + m_trav.speed_variation * std::sin(2 * M_PI * t / kSpeedPeriod_s + m_phaseSpeed));
	double x, y, heading;
	m_scene.route().pointAt(s, lat, x, y, heading);
	// Heading follows the route plus the weave's own slope.
	return mrpt::poses::CPose3D(x, y, 0, heading + std::atan2(latRate, v), 0, 0);
}

// ------------------------------------------------------------------ light
V3 StereoSimulator::sunDirection() const { return m_sun; }

Rgb StereoSimulator::shade(int m, float mix, float b, float sunF, float skyV) const
{
	Rgb out;
	const float sf = sunF * m_sunOn;
	for (int k = 0; k < 3; k++)
		out[k] = b * ((1 - mix) * (sf * m_respSun[m][0][k] + skyV * m_respSky[m][0][k]) +
					  mix * (sf * m_respSun[m][1][k] + skyV * m_respSky[m][1][k]));
	return out;
}

Rgb StereoSimulator::skyRadiance(const V3& d) const
{
	const float up = std::max(d.z, 0.0f);
	Rgb out;
	if (m_sunOn == 0)
	{
		// CIE overcast sky: zenith three times as bright as the horizon;
		// 3/7 normalises it to the horizontal irradiance.
		const float g = (1 + 2 * up) * 3.0f / 7.0f;
		for (int k = 0; k < 3; k++) out[k] = g * m_skyWhite[k];
		return out;
	}
	// Clear sky: brighter towards the horizon, plus a circumsolar glow.
	const float h = 1 - up;
	const float cosA = std::clamp(d.dot(m_sun), -1.0f, 1.0f);
	const float glow = 0.02f * std::exp(40.0f * (cosA - 1.0f)) + (cosA > 0.99996f ? 30.0f : 0.0f);
	for (int k = 0; k < 3; k++)
		out[k] = (0.7f + 0.8f * h * h * h * h) * m_skyWhite[k] + glow * m_sunWhite[k];
	return out;
}

// ------------------------------------------------------------------ rendering
void StereoSimulator::renderLinear(const mrpt::poses::CPose3D& T_world_left, cv::Mat& left, cv::Mat& right,
	TRenderAux* auxL, TRenderAux* auxR) const
{
	const auto& c = m_opts.camera;
	const int W = c.width, H = c.height;
	left.create(H, W, CV_32FC3);
	right.create(H, W, CV_32FC3);
	for (TRenderAux* a : {auxL, auxR})
		if (a)
		{
			a->material.create(H, W, CV_8U);
			a->sun.create(H, W, CV_32F);
			a->depth.create(H, W, CV_32F);
		}
	const auto R = T_world_left.getRotationMatrix();
	float Rw[3][3];
	for (int r = 0; r < 3; r++)
		for (int k = 0; k < 3; k++) Rw[r][k] = static_cast<float>(R(r, k));
	const mrpt::poses::CPose3D T_world_right = T_world_left + T_left_right();
	const V3 origin[2] = {
		V3(static_cast<float>(T_world_left.x()), static_cast<float>(T_world_left.y()),
			static_cast<float>(T_world_left.z())),
		V3(static_cast<float>(T_world_right.x()), static_cast<float>(T_world_right.y()),
			static_cast<float>(T_world_right.z()))};
	const float f = static_cast<float>(c.focalPx()), cx = static_cast<float>(c.cx()), cy = static_cast<float>(c.cy());
	const float tmax = static_cast<float>(m_opts.scene.max_distance_m);
	const float footprint = 1.0f / f;
	cv::Mat* img[2] = {&left, &right};
	TRenderAux* aux[2] = {auxL, auxR};

	cv::parallel_for_(cv::Range(0, 2 * H), [&](const cv::Range& rows) {
		for (int rr = rows.start; rr < rows.end; rr++)
		{
			const int eye = rr / H, v = rr % H;
			float* out = img[eye]->ptr<float>(v);
			uint8_t* am = aux[eye] ? aux[eye]->material.ptr<uint8_t>(v) : nullptr;
			float* as = aux[eye] ? aux[eye]->sun.ptr<float>(v) : nullptr;
			float* ad = aux[eye] ? aux[eye]->depth.ptr<float>(v) : nullptr;
			for (int u = 0; u < W; u++)
			{
				// Pixel centres at integer coordinates (MRPT/OpenCV convention).
				const float xc = (u - cx) / f, yc = (v - cy) / f;
				const float inv = 1.0f / std::sqrt(xc * xc + yc * yc + 1);
				const V3 dc(xc * inv, yc * inv, inv);
				const V3 d(Rw[0][0] * dc.x + Rw[0][1] * dc.y + Rw[0][2] * dc.z,
					Rw[1][0] * dc.x + Rw[1][1] * dc.y + Rw[1][2] * dc.z,
					Rw[2][0] * dc.x + Rw[2][1] * dc.y + Rw[2][2] * dc.z);
				SurfaceHit hit;
				Rgb L;
				float sunT = 0;
				if (m_scene.intersect(origin[eye], d, tmax, footprint * inv, m_wind, hit))
				{
					const float cosS = hit.n.dot(m_sun);
					if (m_sunOn > 0 && cosS > 0) sunT = m_scene.sunTransmittance(hit.p, hit.n, m_sun, m_wind);
					const float skyV = 0.5f * (1.0f + hit.n.z);
					L = shade(hit.material, hit.mix, hit.brightness, sunT * std::max(cosS, 0.0f), skyV);
					if (ad) ad[u] = hit.t * inv;
				}
				else
				{
					L = skyRadiance(d);
					if (ad) ad[u] = 0;
				}
				if (am) am[u] = hit.material;
				if (as) as[u] = sunT;
				out[3 * u + 0] = static_cast<float>(L[0]);	// B
				out[3 * u + 1] = static_cast<float>(L[1]);	// G
				out[3 * u + 2] = static_cast<float>(L[2]);	// R
			}
		}
	});
}

double StereoSimulator::exposureGain(const cv::Mat& lin) const
{
	std::vector<float> y;
	y.reserve(static_cast<size_t>(lin.rows * lin.cols / 4 + 1));
	// Metering ignores the top rows (mostly sky), like a road camera's AE.
	const int top = static_cast<int>(m_opts.camera.exposure_roi_top * lin.rows);
	for (int v = top; v < lin.rows; v += 2)
	{
		const float* p = lin.ptr<float>(v);
		for (int u = 0; u < lin.cols; u += 2)
			y.push_back(0.114f * p[3 * u] + 0.587f * p[3 * u + 1] + 0.299f * p[3 * u + 2]);
	}
	const size_t k = std::min(y.size() - 1, static_cast<size_t>(m_opts.camera.exposure_percentile * (y.size() - 1)));
	std::nth_element(y.begin(), y.begin() + static_cast<long>(k), y.end());
	const double ref = std::max(static_cast<double>(y[k]), 1e-9);
	return m_opts.camera.exposure_target / ref;
}

void StereoSimulator::expose(const cv::Mat& lin, double gain, uint64_t seed, cv::Mat& out8) const
{
	const auto& c = m_opts.camera;
	out8.create(lin.rows, lin.cols, CV_8UC3);
	const float g = static_cast<float>(gain);
	const float ePerLevel = static_cast<float>(c.full_well_e / 255.0);
	const float rn2 = static_cast<float>(c.read_noise_e * c.read_noise_e);
	const bool noise = c.noise;
	cv::parallel_for_(cv::Range(0, lin.rows), [&](const cv::Range& rows) {
		for (int v = rows.start; v < rows.end; v++)
		{
			SplitMix64 rng(seed * 0x9e3779b97f4a7c15ULL + static_cast<uint64_t>(v) * 0x632be59bd9b4e019ULL);
			const float* p = lin.ptr<float>(v);
			uint8_t* o = out8.ptr<uint8_t>(v);
			for (int i = 0; i < 3 * lin.cols; i++)
			{
				float x = g * p[i];
				if (noise)
				{
					// Shot noise (Poisson in electrons, Gaussian approximation)
					// plus read noise; the normal deviate is an Irwin-Hall sum
					// of four 16-bit uniforms (variance 4/12, rescaled).
					const uint64_t r = rng.next();
					const float sum = static_cast<float>((r & 0xffff) + ((r >> 16) & 0xffff) + ((r >> 32) & 0xffff) + (r >> 48)) *
										  (1.0f / 65535.0f) - 2.0f;
					const float sigmaE = std::sqrt(std::max(x, 0.0f) * ePerLevel + rn2);
					x += 1.7320508f * sum * sigmaE / ePerLevel;
				}
				o[i] = static_cast<uint8_t>(std::clamp(std::lround(x), 0L, 255L));
			}
		}
	});
}

TSimFrame StereoSimulator::renderFrame(int frame, TRenderAux* auxL, TRenderAux* auxR)
{
	TSimFrame f;
	f.index = frame;
	f.timestamp = timestamp(frame);
	f.T_world_left = T_world_left(frame);
	f.route_s_m = routePosition(frame);
	cv::Mat linL, linR;
	renderLinear(f.T_world_left, linL, linR, auxL, auxR);
	double gain = exposureGain(linL);
	if (m_prevGain > 0)
	{
		const double s = m_opts.camera.exposure_smoothing;
		gain = std::exp(s * std::log(m_prevGain) + (1 - s) * std::log(gain));
	}
	m_prevGain = gain;
	f.gain = gain;
	const uint64_t base = (static_cast<uint64_t>(m_trav.noise_seed) << 32) ^ (static_cast<uint64_t>(frame) << 1);
	expose(linL, gain, base, f.left);
	expose(linR, gain, base | 1ULL, f.right);
	return f;
}

mrpt::obs::CObservationStereoImages::Ptr StereoSimulator::makeObservation(const TSimFrame& f) const
{
	auto obs = mrpt::obs::CObservationStereoImages::Create();
	obs->sensorLabel = "CAMERA";
	obs->timestamp = mrpt::Clock::fromDouble(f.timestamp);
	obs->imageLeft = mrpt::img::CImage(f.left, mrpt::img::DEEP_COPY);
	obs->imageRight = mrpt::img::CImage(f.right, mrpt::img::DEEP_COPY);
	obs->hasImageRight = true;
	obs->leftCamera = leftCamera();
	obs->rightCamera = leftCamera();
	obs->leftCamera.cameraName = "CAMERA_LEFT";
	obs->rightCamera.cameraName = "CAMERA_RIGHT";
	obs->rightCameraPose = mrpt::poses::CPose3DQuat(T_left_right());
	obs->cameraPose = mrpt::poses::CPose3DQuat(T_vehicle_left());
	return obs;
}

void StereoSimulator::generate(const std::string& rawlogPath, const std::string& tumPath, int frames,
	const std::function<void(const TSimFrame&)>& onFrame, io::OutputTransaction* outputs)
{
	const int n = frames > 0 ? frames : frameCount();
	m_prevGain = 0;
	// Rawlog and ground truth: one transaction, ours or the caller's.
	std::unique_ptr<io::OutputTransaction> own;
	if (!outputs) outputs = (own = std::make_unique<io::OutputTransaction>()).get();
	io::RawlogWriter writer(rawlogPath, false, outputs);
	std::string tumTmp;
	try
	{
		tumTmp = outputs->addFile(tumPath, "ground truth");
	}
	catch (const std::invalid_argument& e)
	{
		throw std::runtime_error(e.what());
	}
	io::Trajectory groundTruth;
	const auto t0 = std::chrono::steady_clock::now();
	// Compressing and writing frame i (~20 ms, one thread) overlaps with
	// rendering frame i+1; at most one write is in flight (the writer is not
	// thread-safe), and get() rethrows a write error here.
	std::future<void> pending;
	for (int i = 0; i < n; i++)
	{
		const TSimFrame f = renderFrame(i);
		auto obs = makeObservation(f);
		if (pending.valid()) pending.get();
		pending = std::async(std::launch::async, [&writer, obs] { writer.write(*obs); });
		groundTruth.push_back({f.timestamp, io::toIsometry(f.T_world_left)});
		if (onFrame) onFrame(f);
		const double el = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
		MRPT_LOG_THROTTLE_INFO_STREAM(
			2.0, m_trav.name << ": frame " << (i + 1) << "/" << n << " (" << std::setprecision(3) << (i + 1) / el
							 << " frames/s)");
	}
	if (pending.valid()) pending.get();
	io::writeTum(
		tumTmp, groundTruth,
		"ground truth of " + std::filesystem::path(rawlogPath).filename().string() + " (traversal " + m_trav.name +
			"): T_world_left, pose of the LEFT camera (z forward, x right, y down) in the world (x east, y north, "
			"z up)");
	writer.commit();
	if (own) own->commit();
	const double el = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
	MRPT_LOG_INFO_STREAM(
		m_trav.name << ": " << n << " frames in " << std::setprecision(3) << el << " s (" << n / el
					<< " frames/s) -> " << rawlogPath);
}

}  // namespace shadyloc::sim
