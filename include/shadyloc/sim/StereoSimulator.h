/* ShadyLoc simulator — physically based stereo rendering of one route driven
 * under different lighting, written as rawlogs with ground truth.
 *
 * Light model (per traversal): direct sun, a black body at T_sun scaled by
 * E_sun, and skylight, a black body at T_sky scaled by E_sky. A Lambertian
 * point with reflectance rho(l), normal n, sun direction s, leaf/solid
 * transmittance V towards the sun and sky-dome visibility v_sky = (1+n_z)/2
 * receives
 *
 *     E(l) = V max(0, n.s) E_sun P(l, T_sun) + v_sky E_sky P(l, T_sky)
 *
 * and the camera channel k (Gaussian sensitivity S_k, white-balance gain w_k)
 * responds R_k = w_k * integral S_k(l) E(l) rho(l) / pi dl. Reflectance is
 * rho = b ((1-m) rho_A + m rho_B) (texture brightness b, chromatic mix m), so
 * R_k is a bilinear mix of eight numbers per material precomputed per
 * traversal (basis A/B x sun/sky): see shade().
 *
 * Sensor: linear; auto-exposure maps a luma percentile of the left image to a
 * target level (smoothed over frames); shot noise (Poisson, Gaussian
 * approximation) and read noise in electrons; 8-bit quantisation; BGR out.
 * No gamma: the images are linear (invariant filter: linearisation = none).
 *
 * Frames: world x east, y north, z up. Vehicle frame x forward, y left, z up,
 * on the ground. Cameras: z forward, x right, y down (MRPT/OpenCV); the left
 * camera sits baseline/2 left of the vehicle's centre line; the right camera
 * is at +baseline along the left camera's x axis. Ground truth is
 * T_world_left: the pose of the LEFT camera in the world.
 */
#pragma once

#include <shadyloc/sim/Scene.h>
#include <shadyloc/sim/SimOptions.h>
#include <shadyloc/sim/Spectral.h>

#include <mrpt/img/TCamera.h>
#include <mrpt/obs/CObservationStereoImages.h>
#include <mrpt/poses/CPose3D.h>
#include <mrpt/system/COutputLogger.h>

#include <opencv2/core/mat.hpp>

#include <functional>
#include <string>

namespace shadyloc::io
{
class OutputTransaction;
}

namespace shadyloc::sim
{
/** Per-pixel by-products of a render, for tests and inspection. */
struct TRenderAux
{
	cv::Mat material;  //!< CV_8U, Material of the visible surface (kSky = none)
	cv::Mat sun;  //!< CV_32F, transmittance towards the sun in [0,1] (0 when overcast)
	cv::Mat depth;	//!< CV_32F, z in the camera frame (m), 0 for sky
};

/** One rendered stereo frame. */
struct TSimFrame
{
	int index = 0;
	double timestamp = 0;  //!< s (UNIX)
	mrpt::poses::CPose3D T_world_left;	//!< ground truth: left camera in the world
	cv::Mat left, right;  //!< CV_8UC3, BGR, linear
	double gain = 0;  //!< exposure: grey levels per unit of linear response
	double route_s_m = 0;  //!< route arc length of the vehicle (m)
};

class StereoSimulator : public mrpt::system::COutputLogger
{
   public:
	/** Builds the scene; selects the first traversal (if any). */
	explicit StereoSimulator(const TSimOptions& opts);

	const TSimOptions& options() const { return m_opts; }
	Scene& scene() { return m_scene; }
	const Scene& scene() const { return m_scene; }

	/** Selects the lighting and path; precomputes the spectral responses and
	 * resets auto-exposure. */
	void setTraversal(const TTraversal& t);
	const TTraversal& traversal() const { return m_trav; }

	// ---- geometry
	mrpt::img::TCamera leftCamera() const;	//!< = right camera (rectified pair)
	mrpt::poses::CPose3D T_vehicle_left() const;  //!< left camera on the vehicle
	mrpt::poses::CPose3D T_left_right() const;	//!< (baseline, 0, 0), identity rotation
	/** Vehicle pose at frame i of the current traversal. */
	mrpt::poses::CPose3D T_world_vehicle(int frame) const;
	mrpt::poses::CPose3D T_world_left(int frame) const { return T_world_vehicle(frame) + T_vehicle_left(); }
	double timestamp(int frame) const;
	/** Route arc length (m) of the vehicle at frame i. */
	double routePosition(int frame) const;
	/** Frames of the current traversal: its `frames`, or with end_s_m the
	 * count up to and including the first frame at or past end_s_m (the
	 * speed never drops to zero, so route position grows with the frame).
	 * Throws std::invalid_argument when that takes more than 1e6 frames. */
	int frameCount() const;

	// ---- light
	/** Unit vector towards the sun, world frame. */
	V3 sunDirection() const;
	/** Linear camera response (before exposure) of a point of material m,
	 * texture (mix, brightness), direct-sun factor V*max(0, n.s) and sky
	 * visibility: the shading function every pixel goes through. */
	Rgb shade(int material, float mix, float brightness, float sunFactor, float skyVisibility) const;
	/** Linear response of the sky seen along unit direction d (world). */
	Rgb skyRadiance(const V3& d) const;

	// ---- rendering
	/** Linear (CV_32FC3, BGR) images of both eyes from a left-camera pose. */
	void renderLinear(const mrpt::poses::CPose3D& T_world_left, cv::Mat& left, cv::Mat& right,
		TRenderAux* auxLeft = nullptr, TRenderAux* auxRight = nullptr) const;
	/** Auto-exposure gain for a linear left image: percentile luma -> target. */
	double exposureGain(const cv::Mat& linearLeft) const;
	/** gain, noise and 8-bit quantisation; deterministic in (seed, row). */
	void expose(const cv::Mat& linear, double gain, uint64_t seed, cv::Mat& out8) const;
	/** Renders frame i (call in order: auto-exposure is smoothed over frames). */
	TSimFrame renderFrame(int frame, TRenderAux* auxLeft = nullptr, TRenderAux* auxRight = nullptr);

	/** The rawlog observation of a frame: sensorLabel "CAMERA", BGR images,
	 * calibration, rightCameraPose, cameraPose = T_vehicle_left. */
	mrpt::obs::CObservationStereoImages::Ptr makeObservation(const TSimFrame& f) const;

	/** Renders the current traversal (frames <= 0: frameCount()) to
	 * rawlogPath and its ground truth (TUM, T_world_left) to tumPath. Both
	 * appear only if everything succeeded. onFrame sees each frame. With
	 * `outputs`, both are outputs of that transaction (put in place by its
	 * commit(), with the command's other outputs); otherwise of their own. */
	void generate(const std::string& rawlogPath, const std::string& tumPath, int frames = -1,
		const std::function<void(const TSimFrame&)>& onFrame = {}, io::OutputTransaction* outputs = nullptr);

   private:
	TSimOptions m_opts;
	Scene m_scene;
	TTraversal m_trav;
	V3 m_sun, m_wind;
	float m_sunOn = 0;	//!< 1 if there is direct sun
	float m_respSun[kMaterialCount][2][3], m_respSky[kMaterialCount][2][3];
	float m_skyWhite[3], m_sunWhite[3];	 //!< white-reflector responses (sky, sun)
	double m_prevGain = 0;	//!< auto-exposure state
	double m_phaseSpeed = 0, m_phaseWeave = 0;
};

}  // namespace shadyloc::sim
