/* ShadyLoc — the localiser's core for a single image (2D-3D) against a
 * stereo keyframe (include/shadyloc/localisation/MonocularLocaliser.h). */
#include <shadyloc/core/Options.h>
#include <shadyloc/core/Units.h>
#include <shadyloc/localisation/LocalisationSystem.h>
#include <shadyloc/localisation/MonocularLocaliser.h>

#include <mrpt/img/TCamera.h>
#include <mrpt/obs/CObservationImage.h>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace shadyloc::localisation
{
using geometry::Matrix6d;
using geometry::Vector6d;

namespace
{
using core::kDeg;

Eigen::Matrix3d skew(const Eigen::Vector3d& v)
{
	Eigen::Matrix3d S;
	S << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
	return S;
}


/** Residual of one correspondence at T (= T_curr_ref): r, J = dr/dxi (left
 * perturbation), Sigma = its covariance. False if the point is behind. */
bool imageResidual(
	const TPinholeCalib& calib, const Eigen::Isometry3d& T, const TImageCorrespondence& c, double sigma_px,
	Eigen::Vector2d& r, Eigen::Matrix<double, 2, 6>& J, Eigen::Matrix2d& Sigma)
{
	const Eigen::Vector3d p = T * c.P_ref;
	if (!(p.z() > 1e-3)) return false;
	Eigen::Matrix<double, 2, 3> Jp;
	r = calib.project(p, &Jp) - c.z;
	// d(exp(xi) T P)/dxi at 0 = [I, -[p]x] (xi = (rho, phi)).
	J.leftCols<3>() = Jp;
	J.rightCols<3>() = -Jp * skew(p);
	const Eigen::Matrix<double, 2, 3> JP = Jp * T.linear();
	Sigma = sigma_px * sigma_px * Eigen::Matrix2d::Identity() + JP * c.cov_ref * JP.transpose();
	return true;
}

/** Landmark j's feature (-1: none) and its descriptor distance. */
struct TLandmarkMatches
{
	explicit TLandmarkMatches(size_t n) : feature(n, -1), distance(n, 257) {}
	std::vector<int> feature, distance;
};

/** The best feature of a landmark among those `consider` admits, if it
 * passes the distance bound and the ratio test. */
template <typename Admit>
void bestFeature(
	const features::TStereoMeasurement& lm, const TImageFeatures& f, const TMonocularLocaliserOptions& o, Admit&& consider,
	int& feature, int& distance)
{
	int b1 = 257, b2 = 257, bi = -1;
	for (size_t i = 0; i < f.feats.size(); i++)
	{
		if (!consider(i)) continue;
		const int d = features::hamming(lm.desc, f.feats[i].desc);
		if (d < b1) b2 = b1, b1 = d, bi = static_cast<int>(i);
		else if (d < b2) b2 = d;
	}
	if (bi >= 0 && b1 <= o.max_hamming && b1 < o.match_ratio * b2) feature = bi, distance = b1;
}

/** Without a prediction every feature is a candidate: ratio test on the
 * landmark's side, then (option) mutual. */
void matchEverywhere(
	const std::vector<features::TStereoMeasurement>& lms, const TImageFeatures& f, const TMonocularLocaliserOptions& o,
	TLandmarkMatches& m)
{
	const size_t nF = f.feats.size();
	std::vector<int> bestLm(nF, -1), bestLmDist(nF, 257);
	for (size_t j = 0; j < lms.size(); j++)
	{
		// Both sides in one pass over the distances: the landmark's best two, each feature's best landmark.
		int b1 = 257, b2 = 257, bi = -1;
		for (size_t i = 0; i < nF; i++)
		{
			const int d = features::hamming(lms[j].desc, f.feats[i].desc);
			if (d < bestLmDist[i]) bestLmDist[i] = d, bestLm[i] = static_cast<int>(j);
			if (d < b1) b2 = b1, b1 = d, bi = static_cast<int>(i);
			else if (d < b2) b2 = d;
		}
		if (bi >= 0 && b1 <= o.max_hamming && b1 < o.match_ratio * b2) m.feature[j] = bi, m.distance[j] = b1;
	}
	if (!o.mutual) return;
	for (size_t j = 0; j < lms.size(); j++)
		if (m.feature[j] >= 0 && bestLm[static_cast<size_t>(m.feature[j])] != static_cast<int>(j)) m.feature[j] = -1;
}

/** One landmark per feature: the closer descriptor keeps it. */
void oneLandmarkPerFeature(size_t nFeatures, TLandmarkMatches& m)
{
	std::vector<int> owner(nFeatures, -1);
	for (size_t j = 0; j < m.feature.size(); j++)
	{
		if (m.feature[j] < 0) continue;
		int& w = owner[static_cast<size_t>(m.feature[j])];
		if (w < 0) w = static_cast<int>(j);
		else if (m.distance[j] < m.distance[static_cast<size_t>(w)])
		{
			m.feature[static_cast<size_t>(w)] = -1;
			w = static_cast<int>(j);
		}
		else
			m.feature[j] = -1;
	}
}

/** With a prediction: each landmark searched in the chi-square gate of its
 * predicted pixel (first order, with a floor; a gate longer than
 * gate_max_px is not searched, never clipped). False (lost) when too many
 * gates overflow. */
bool matchInGates(
	const std::vector<features::TStereoMeasurement>& lms, const TImageFeatures& f, const TPinholeCalib& calib,
	const TKeyframePose& prediction, const TMonocularLocaliserOptions& o, TLandmarkMatches& m, vo::TGateStats& gate)
{
	const Eigen::Isometry3d T_live_kf = prediction.T_kf_live.inverse();
	const Matrix6d covT = geometry::invertCovariance(prediction.T_kf_live, prediction.cov);
	std::vector<double> axes;
	const double minL = o.gate_min_px * o.gate_min_px / o.gate_chi2;
	for (size_t j = 0; j < lms.size(); j++)
	{
		const Eigen::Vector3d p = T_live_kf * lms[j].P;
		if (!(p.z() > 0.1)) continue;
		Eigen::Matrix<double, 2, 3> Jp;
		const Eigen::Vector2d z = calib.project(p, &Jp);
		if (z.x() < 0 || z.y() < 0 || z.x() >= f.image.cols || z.y() >= f.image.rows) continue;
		Eigen::Matrix<double, 2, 6> Jx;
		Jx.leftCols<3>() = Jp;
		Jx.rightCols<3>() = -Jp * skew(p);
		const Eigen::Matrix<double, 2, 3> JP = Jp * T_live_kf.linear();
		const Eigen::Matrix2d S = JP * lms[j].cov * JP.transpose() + Jx * covT * Jx.transpose() +
								  o.sigma_px * o.sigma_px * Eigen::Matrix2d::Identity();
		Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> es(0.5 * (S + S.transpose()));
		gate.predicted++;
		const double longest = std::sqrt(o.gate_chi2 * std::max(0.0, es.eigenvalues().maxCoeff()));
		axes.push_back(longest);
		if (longest > o.gate_max_px)
		{
			gate.overflow++;  // never clipped: not searched
			continue;
		}
		const Eigen::Vector2d lam = es.eigenvalues().cwiseMax(minL);
		const Eigen::Matrix2d Ginv = es.eigenvectors() * lam.cwiseInverse().asDiagonal() * es.eigenvectors().transpose();
		const auto inGate = [&](size_t i) {
			const Eigen::Vector2d dz(f.feats[i].u - z.x(), f.feats[i].v - z.y());
			if (std::abs(dz.x()) > o.gate_max_px || std::abs(dz.y()) > o.gate_max_px) return false;
			return dz.dot(Ginv * dz) <= o.gate_chi2;
		};
		bestFeature(lms[j], f, o, inGate, m.feature[j], m.distance[j]);
	}
	if (!axes.empty())
	{
		std::nth_element(axes.begin(), axes.begin() + axes.size() / 2, axes.end());
		gate.median_axis_px = axes[axes.size() / 2];
	}
	if (gate.predicted > 0 && gate.overflow > o.max_overflow_fraction * gate.predicted) return false;
	oneLandmarkPerFeature(f.feats.size(), m);
	return true;
}

/** Each matched landmark's keyframe patch located to sub-pixel in the image;
 * `descriptorMatches` counts the matches tried. */
std::vector<TImageCorrespondence> refineMatches(
	const std::vector<features::TStereoMeasurement>& lms, const TImageFeatures& f, const TMonocularLocaliserOptions& o,
	const TLandmarkMatches& m, int& descriptorMatches)
{
	std::vector<TImageCorrespondence> corr;
	for (size_t j = 0; j < lms.size(); j++)
	{
		if (m.feature[j] < 0) continue;
		descriptorMatches++;
		const auto& ft = f.feats[static_cast<size_t>(m.feature[j])];
		float xs, ys;
		if (!features::locatePatch(
				lms[j].patch, f.image, static_cast<int>(ft.u), static_cast<int>(ft.v), o.refine_radius_px,
				o.refine_min_zncc, o.refine_iterations, xs, ys))
			continue;
		corr.push_back({lms[j].P, lms[j].cov, Eigen::Vector2d(xs, ys)});
	}
	return corr;
}

/** OpenCV's PnP RANSAC (AP3P): T_curr_ref, or none (also for degenerate
 * sets); `use` marks its inliers, `inliers` counts them. */
std::optional<Eigen::Isometry3d> pnpRansac(
	const std::vector<TImageCorrespondence>& corr, const TPinholeCalib& calib, const TMonocularLocaliserOptions& o,
	std::vector<uint8_t>& use, int& inliers)
{
	std::vector<cv::Point3d> obj;
	std::vector<cv::Point2d> pix;
	for (const auto& k : corr)
	{
		obj.emplace_back(k.P_ref.x(), k.P_ref.y(), k.P_ref.z());
		pix.emplace_back(k.z.x(), k.z.y());
	}
	const cv::Matx33d K(calib.fx, 0, calib.cx, 0, calib.fy, calib.cy, 0, 0, 1);
	cv::Mat rvec, tvec;
	std::vector<int> inl;
	bool ok = false;
	try
	{
		ok = cv::solvePnPRansac(
			obj, pix, K, cv::noArray(), rvec, tvec, false, o.ransac_iterations,
			static_cast<float>(o.ransac_threshold_px), o.ransac_confidence, inl, cv::SOLVEPNP_AP3P);
	}
	catch (const cv::Exception&)
	{
		ok = false;	 // degenerate sets: no pose
	}
	inliers = static_cast<int>(inl.size());
	if (!ok) return std::nullopt;
	use.assign(corr.size(), 0);
	for (const int i : inl) use[static_cast<size_t>(i)] = 1;
	cv::Mat Rcv;
	cv::Rodrigues(rvec, Rcv);
	Eigen::Matrix3d R;
	cv::cv2eigen(Rcv, R);
	Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
	T.linear() = R;
	T.translation() = Eigen::Vector3d(tvec.at<double>(0), tvec.at<double>(1), tvec.at<double>(2));
	return T;
}

/** Inliers re-selected at pose T: marks `use`, returns their count. */
int reselectInliers(
	const std::vector<TImageCorrespondence>& corr, const TPinholeCalib& calib, const Eigen::Isometry3d& T,
	double threshold_px, std::vector<uint8_t>& use)
{
	int n = 0;
	for (size_t i = 0; i < corr.size(); i++)
	{
		const Eigen::Vector3d p = T * corr[i].P_ref;
		use[i] = p.z() > 1e-3 && (calib.project(p) - corr[i].z).norm() < threshold_px;
		n += use[i];
	}
	return n;
}

}  // namespace

// ---- the camera ------------------------------------------------------------------------------------
TPinholeCalib TPinholeCalib::LeftOf(const geometry::TStereoCalib& c) { return {c.fx, c.fy, c.cx, c.cy}; }
TPinholeCalib TPinholeCalib::RightOf(const geometry::TStereoCalib& c) { return {c.fx, c.fy, c.cxR, c.cy}; }

TPinholeCalib TPinholeCalib::FromCamera(const mrpt::img::TCamera& cam)
{
	for (const double d : cam.dist)
		if (d != 0)
			throw std::invalid_argument(
				"camera '" + cam.cameraName + "' has lens distortion: the 2D-3D localiser needs undistorted images");
	if (!(cam.fx() > 0 && cam.fy() > 0))
		throw std::invalid_argument("camera '" + cam.cameraName + "': focal lengths must be positive");
	return {cam.fx(), cam.fy(), cam.cx(), cam.cy()};
}

Eigen::Vector2d TPinholeCalib::project(const Eigen::Vector3d& P, Eigen::Matrix<double, 2, 3>* J) const
{
	const double iz = 1.0 / P.z();
	if (J) *J << fx * iz, 0, -fx * P.x() * iz * iz, 0, fy * iz, -fy * P.y() * iz * iz;
	return {fx * P.x() * iz + cx, fy * P.y() * iz + cy};
}

std::string TPinholeCalib::asString() const
{
	std::ostringstream s;
	s << "fx=" << fx << " fy=" << fy << " cx=" << cx << " cy=" << cy;
	return s.str();
}

// ---- features --------------------------------------------------------------------------------------
void extractImageFeatures(
	const cv::Mat& grey8, const features::TStereoFeatureOptions& fo, int perCell, TImageFeatures& out)
{
	if (grey8.empty() || grey8.type() != CV_8UC1)
		throw std::invalid_argument("extractImageFeatures: needs a non-empty CV_8UC1 image");
	out.feats.clear();
	// As StereoFeatureExtractor::process does for the left image: the same
	// smoothing, detector, border and descriptor (features::CornerDescriber).
	cv::Mat img = grey8;
	if (fo.presmooth_sigma > 0) cv::GaussianBlur(grey8, img, cv::Size(), fo.presmooth_sigma);
	out.image = img;
	const features::CornerDescriber corners(fo);
	std::vector<cv::KeyPoint> kp;
	corners.detect(img, perCell, corners.border(), kp);
	std::vector<features::TBriefDescriptor> desc;
	std::vector<uint8_t> ok;
	corners.describe(img, kp, desc, ok);
	out.feats.reserve(kp.size());
	for (size_t i = 0; i < kp.size(); i++)
	{
		if (!ok[i]) continue;
		TImageFeature f;
		f.u = std::floor(kp[i].pt.x);
		f.v = std::floor(kp[i].pt.y);
		f.response = kp[i].response;
		f.desc = desc[i];
		out.feats.push_back(f);
	}
}

// ---- options ---------------------------------------------------------------------------------------
void TMonocularLocaliserOptions::keys(core::KeyVisitor& v)
{
	using core::Range;
	v("corners_per_cell", corners_per_cell, "", Range::closed(1, 10000), "FAST corners kept per grid bucket");
	v("max_hamming", max_hamming, "bits of 256", Range::closed(0, 256), "");
	v("match_ratio", match_ratio, "", Range::openClosed(0, 1), "best < ratio * second best");
	v("mutual", mutual, "", Range::any(), "no prior: mutual best matches only");
	v("gate_chi2", gate_chi2, "", Range::above(0), "with a prior: chi^2, 2 dof");
	v("gate_min_px", gate_min_px, "px", Range::above(0), "");
	v("gate_max_px", gate_max_px, "px", Range::atMost(10000), "ceiling: not searched beyond");
	v("max_overflow_fraction", max_overflow_fraction, "", Range::closed(0, 1), "");
	v("refine_min_zncc", refine_min_zncc, "", Range::closed(-1, 1), "");
	v("refine_radius_px", refine_radius_px, "px", Range::closed(0, 20), "");
	v("refine_iterations", refine_iterations, "", Range::closed(0, 50), "");
	v("ransac_threshold_px", ransac_threshold_px, "px", Range::above(0), "PnP RANSAC inlier bound");
	v("ransac_iterations", ransac_iterations, "", Range::closed(1, 1e6), "");
	v("ransac_confidence", ransac_confidence, "", Range::open(0, 1), "");
	v("sigma_px", sigma_px, "px", Range::above(0), "");
	v("huber_k", huber_k, "sigmas", Range::above(0), "");
	v("max_iterations", max_iterations, "", Range::closed(1, 1000), "Gauss-Newton iterations");
	v("cov_scale", cov_scale, "", Range::above(0), "");
	// PnP needs four points.
	v("min_matches", min_matches, "", Range::atLeast(4), "");
	v("min_inliers", min_inliers, "", Range::atLeast(4), "");
	v("max_sigma_m", max_sigma_m, "m", Range::above(0), "");
	v("max_sigma_deg", max_sigma_deg, "deg", Range::above(0), "");
}

void TMonocularLocaliserOptions::load(const mrpt::config::CConfigFileBase& c, const std::string& s) { core::loadKeys(*this, c, s); }

void TMonocularLocaliserOptions::dump(std::ostream& out) const { core::dumpKeys(*this, out); }

void TMonocularLocaliserOptions::validate() const
{
	core::checkKeys(*this);
	if (!(gate_min_px <= gate_max_px)) throw std::invalid_argument("gate_min_px: must be <= gate_max_px");
}

TMonocularLocaliserOptions monocularLocaliserOptionsFor(
	const mrpt::config::CConfigFileBase& cfg, const std::string& channel, const std::string& section)
{
	TMonocularLocaliserOptions o;
	if (cfg.sectionExists(section)) o.load(cfg, section);
	const std::string over = section + "." + channel;
	if (cfg.sectionExists(over)) o.load(cfg, over);
	return o;
}

// ---- the solve -------------------------------------------------------------------------------------
geometry::TPoseSolution solveImagePose(
	const TPinholeCalib& calib, const std::vector<TImageCorrespondence>& c, const std::vector<uint8_t>& use,
	const Eigen::Isometry3d& T_init, double sigma_px, double huber_k, int max_iterations)
{
	geometry::TPoseSolution s;
	Eigen::Isometry3d T = T_init;
	// One pass: normal equations with the Huber weights at T, the cost.
	const auto accumulate = [&](const Eigen::Isometry3d& X, Matrix6d& H, Vector6d& g, double& cost, double& sq, int& n) {
		H.setZero();
		g.setZero();
		cost = sq = 0;
		n = 0;
		for (size_t i = 0; i < c.size(); i++)
		{
			if (!use.empty() && !use[i]) continue;
			Eigen::Vector2d r;
			Eigen::Matrix<double, 2, 6> J;
			Eigen::Matrix2d S;
			if (!imageResidual(calib, X, c[i], sigma_px, r, J, S)) continue;
			const Eigen::Matrix2d W = S.inverse();
			const double e = std::sqrt(std::max(0.0, r.dot(W * r)));
			const double w = e <= huber_k ? 1.0 : huber_k / e;
			H += w * J.transpose() * W * J;
			g += w * J.transpose() * W * r;
			cost += e <= huber_k ? 0.5 * e * e : huber_k * (e - 0.5 * huber_k);
			sq += r.squaredNorm();
			n++;
		}
	};
	Matrix6d H;
	Vector6d g;
	double cost = 0, sq = 0;
	int n = 0;
	accumulate(T, H, g, cost, sq, n);
	if (n < 3) return s;
	for (int it = 0; it < max_iterations; it++)
	{
		const Eigen::LDLT<Matrix6d> ldlt(H);
		if (ldlt.info() != Eigen::Success || !ldlt.isPositive()) return s;
		const Vector6d dx = -ldlt.solve(g);
		if (!dx.allFinite()) return s;
		// Accept a step only when the robust cost does not grow (halving otherwise).
		double step = 1.0;
		bool taken = false;
		for (int k = 0; k < 6 && !taken; k++, step *= 0.5)
		{
			const Eigen::Isometry3d Tn = geometry::retractLeft(step * dx, T);
			Matrix6d Hn;
			Vector6d gn;
			double cn = 0, sqn = 0;
			int nn = 0;
			accumulate(Tn, Hn, gn, cn, sqn, nn);
			if (nn >= 3 && cn <= cost)
			{
				T = Tn;
				H = Hn;
				g = gn;
				cost = cn;
				sq = sqn;
				n = nn;
				taken = true;
			}
		}
		s.iterations = it + 1;
		if (!taken || (step * 2) * dx.norm() < 1e-10) break;
	}
	const Eigen::LDLT<Matrix6d> ldlt(H);
	if (ldlt.info() != Eigen::Success || !ldlt.isPositive()) return s;
	const Matrix6d covCurrRef = ldlt.solve(Matrix6d::Identity());
	if (!covCurrRef.allFinite()) return s;
	s.ok = true;
	s.T_curr_ref = T;
	s.cov_T_ref_curr = geometry::invertCovariance(T, 0.5 * (covCurrRef + covCurrRef.transpose()));
	s.rms_px = std::sqrt(sq / n);
	return s;
}

// ---- the localiser ---------------------------------------------------------------------------------
MonocularLocaliser::MonocularLocaliser(
	const CKeyframeMap& map, const filters::TChannel& channel, const features::TStereoFeatureOptions& fo,
	const TMonocularLocaliserOptions& o)
	: m_map(map), m_channel(channel), m_fo(fo), m_opts(o)
{
	if (!channel.filter) throw std::invalid_argument("MonocularLocaliser: channel '" + channel.label + "' has no filter");
	m_opts.validate();
	fo.validate();
	map.channelIndex(channel.label);  // throws naming the map's channels
	map.checkCompatible(LocalisationSystem::liveParams(channel, fo));
}

TImageFeatures MonocularLocaliser::features(const cv::Mat& image) const
{
	cv::Mat grey;
	m_channel.convert(image, grey);
	TImageFeatures f;
	extractImageFeatures(grey, m_fo, m_opts.corners_per_cell, f);
	return f;
}

TMonocularLocaliserResult MonocularLocaliser::localise(
	const cv::Mat& image, const TPinholeCalib& calib, uint32_t kf, const std::optional<TKeyframePose>& prediction) const
{
	const auto t0 = std::chrono::steady_clock::now();
	auto r = localise(features(image), calib, kf, prediction);
	r.ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
	return r;
}

TMonocularLocaliserResult MonocularLocaliser::localise(
	const mrpt::obs::CObservationImage& obs, uint32_t kf, const std::optional<TKeyframePose>& prediction) const
{
	if (obs.image.isEmpty())
		throw std::invalid_argument("observation '" + obs.sensorLabel + "': image not loaded");
	return localise(obs.image.asCvMatRef(), TPinholeCalib::FromCamera(obs.cameraParams), kf, prediction);
}

TMonocularLocaliserResult MonocularLocaliser::localise(
	const TImageFeatures& f, const TPinholeCalib& calib, uint32_t kf, const std::optional<TKeyframePose>& prediction) const
{
	const auto t0 = std::chrono::steady_clock::now();
	const auto& o = m_opts;
	TMonocularLocaliserResult r;
	r.channel = m_channel.label;
	r.kf_id = kf;
	r.features = static_cast<int>(f.feats.size());
	if (kf >= m_map.keyframeCount())
		throw std::out_of_range(
			"MonocularLocaliser: keyframe " + std::to_string(kf) + " is not in the map (" +
			std::to_string(m_map.keyframeCount()) + " keyframes)");
	if (prediction && prediction->valid && prediction->kf != kf)
		throw std::invalid_argument(
			"MonocularLocaliser: the prediction is relative to keyframe " + std::to_string(prediction->kf) + ", not " +
			std::to_string(kf));
	const auto& lms = m_map.measurements(kf, m_channel.label);
	const auto done = [&](LocaliserStatus s) {
		r.status = s;
		r.ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
		return r;
	};
	const cv::Mat& img = f.image;
	if (lms.empty() || f.feats.empty() || img.empty()) return done(LocaliserStatus::FewMatches);

	// ---- matching: landmark j -> feature matchOf[j]
	TLandmarkMatches m(lms.size());
	if (!prediction || !prediction->valid) matchEverywhere(lms, f, o, m);
	else if (!matchInGates(lms, f, calib, *prediction, o, m, r.gate))
		return done(LocaliserStatus::Lost);

	// ---- sub-pixel: the keyframe's patch located in the image
	const std::vector<TImageCorrespondence> corr = refineMatches(lms, f, o, m, r.descriptor_matches);
	r.matches = static_cast<int>(corr.size());
	if (r.matches < o.min_matches) return done(LocaliserStatus::FewMatches);

	// ---- PnP RANSAC (OpenCV), then the robust refinement
	std::vector<uint8_t> use;
	const auto T0 = pnpRansac(corr, calib, o, use, r.ransac_inliers);
	if (!T0 || r.ransac_inliers < o.min_inliers) return done(LocaliserStatus::FewInliers);
	Eigen::Isometry3d T = *T0;
	for (int pass = 0; pass < 2; pass++)
	{
		const auto sol = solveImagePose(calib, corr, use, T, o.sigma_px, o.huber_k, o.max_iterations);
		if (!sol.ok) return done(LocaliserStatus::SolverFailed);
		T = sol.T_curr_ref;
		r.inliers = reselectInliers(corr, calib, T, o.ransac_threshold_px, use);
		if (r.inliers < o.min_inliers) return done(LocaliserStatus::FewInliers);
	}
	const auto sol = solveImagePose(calib, corr, use, T, o.sigma_px, o.huber_k, o.max_iterations);
	if (!sol.ok) return done(LocaliserStatus::SolverFailed);
	r.solved = true;
	r.T_kf_live = sol.T_curr_ref.inverse();
	r.cov = o.cov_scale * sol.cov_T_ref_curr;
	r.rms_px = sol.rms_px;
	r.sigma_m = geometry::translationSigma(r.cov);
	r.sigma_deg = geometry::rotationSigma(r.cov) / kDeg;
	if (r.sigma_m > o.max_sigma_m || r.sigma_deg > o.max_sigma_deg) return done(LocaliserStatus::Uncertain);
	return done(LocaliserStatus::Ok);
}

}  // namespace shadyloc::localisation
