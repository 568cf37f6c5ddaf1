/* ShadyLoc — keyframe-based stereo VO. */
#include <shadyloc/vo/StereoVO.h>


#include <algorithm>
#include <chrono>
#include <cmath>
#include <ostream>
#include <stdexcept>

namespace shadyloc::vo
{
using geometry::Matrix6d;
using Clock = std::chrono::steady_clock;

namespace
{
double msSince(Clock::time_point t0)
{
	return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}
double rotationDeg(const Eigen::Isometry3d& T)
{
	return Eigen::AngleAxisd(T.linear()).angle() * 180.0 / M_PI;
}

/** ZNCC of a stored kPatchSize^2 patch against the image window at (x, y). */
float patchZncc(const std::array<uint8_t, features::kPatchSize * features::kPatchSize>& p, const cv::Mat& img, int x, int y)
{
	constexpr int N = features::kPatchSize, h = N / 2;
	int sa = 0, sb = 0;
	int64_t saa = 0, sbb = 0, sab = 0;
	for (int dy = 0; dy < N; dy++)
	{
		const uint8_t* row = img.ptr<uint8_t>(y - h + dy) + x - h;
		const uint8_t* pr = p.data() + dy * N;
		for (int dx = 0; dx < N; dx++)
		{
			const int a = pr[dx], b = row[dx];
			sa += a;
			sb += b;
			saa += a * a;
			sbb += b * b;
			sab += a * b;
		}
	}
	const double n = N * N;
	const double va = saa - double(sa) * sa / n, vb = sbb - double(sb) * sb / n;
	if (va < 1e-6 || vb < 1e-6) return -1.f;
	return static_cast<float>((sab - double(sa) * sb / n) / std::sqrt(va * vb));
}

/** Uniform grid over the current measurements for window queries. */
struct MeasGrid
{
	static constexpr int kCell = 16;
	int cols = 0, rows = 0;
	std::vector<std::vector<int>> cells;
	void build(const std::vector<features::TStereoMeasurement>& m, int W, int H)
	{
		cols = (W + kCell - 1) / kCell;
		rows = (H + kCell - 1) / kCell;
		cells.assign(static_cast<size_t>(cols * rows), {});
		for (size_t i = 0; i < m.size(); i++)
			cells[static_cast<int>(m[i].v) / kCell * cols + static_cast<int>(m[i].uL) / kCell].push_back(
				static_cast<int>(i));
	}
};
}  // namespace

std::string toString(FrameStatus s)
{
	switch (s)
	{
		case FrameStatus::Ok: return "ok";
		case FrameStatus::First: return "first";
		case FrameStatus::FewFeatures: return "few_features";
		case FrameStatus::FewMatches: return "few_matches";
		case FrameStatus::FewInliers: return "few_inliers";
		case FrameStatus::SolverFailed: return "solver_failed";
		case FrameStatus::WildMotion: return "wild_motion";
		case FrameStatus::Reinit: return "reinit";
	}
	return "?";
}

// ---- the pipeline -------------------------------------------------------------
StereoVO::StereoVO(const TOptions& o, const features::TStereoFeatureOptions& fo)
	: mrpt::system::COutputLogger("StereoVO"), m_opts(o), m_extractor(fo)
{
	m_opts.validate();
}

void StereoVO::reset()
{
	m_keyframes.clear();
	m_frame = 0;
	m_lost = 0;
	m_T_world_prev.setIdentity();
	m_velocity.setIdentity();
}

TFrameResult StereoVO::process(
	const cv::Mat& left8, const cv::Mat& right8, const geometry::TStereoCalib& calib, double timestamp,
	const Eigen::Isometry3d* prior)
{
	const auto tStart = Clock::now();
	const auto& o = m_opts;
	TFrameResult res;
	res.frame = m_frame++;
	res.timestamp = timestamp;

	features::TStereoFrame fr;
	m_extractor.process(left8, right8, calib, fr);
	res.features = fr.cornersLeft;
	res.stereo = fr.meas.size();
	res.ms.detect = fr.timings.detect_ms;
	res.ms.stereo = fr.timings.stereo_ms;
	res.ms.describe = fr.timings.describe_ms;

	const Eigen::Isometry3d V =
		prior ? *prior : (o.constant_velocity ? m_velocity : Eigen::Isometry3d::Identity());
	const Eigen::Isometry3d T_world_pred = m_T_world_prev * V;

	auto makeKeyframe = [&](const Eigen::Isometry3d& T_world_kf, const Matrix6d& cov, bool brk) {
		TKeyframe kf;
		kf.id = static_cast<uint32_t>(m_keyframes.size());
		kf.frame = res.frame;
		kf.timestamp = timestamp;
		kf.T_world_kf = T_world_kf;
		kf.T_prevkf_kf =
			m_keyframes.empty() ? Eigen::Isometry3d::Identity() : m_keyframes.back().T_world_kf.inverse() * T_world_kf;
		kf.cov = cov;
		kf.chain_break = brk;
		kf.meas = std::move(fr.meas);
		m_keyframes.push_back(std::move(kf));
		res.keyframe = true;
	};
	auto finish = [&](const Eigen::Isometry3d& T_world_curr) {
		res.T_world_curr = T_world_curr;
		m_T_world_prev = T_world_curr;
		res.ms.total = msSince(tStart);
		return res;
	};
	// Untracked frame: predicted pose; after too many, restart a chain segment.
	auto fail = [&](FrameStatus st) {
		res.status = st;
		m_lost++;
		MRPT_LOG_THROTTLE_WARN_FMT(
			2.0, "frame %zu: %s (stereo %zu, tracked %zu, inliers %zu); predicted pose kept",
			res.frame, toString(st).c_str(), res.stereo, res.tracked, res.inliers);
		if (m_lost > o.max_lost_frames && static_cast<int>(res.stereo) >= o.min_stereo &&
			!m_keyframes.empty())
		{
			// A chain break: the link is a prediction, with a deliberately large covariance.
			const Matrix6d big = Matrix6d::Identity() * 1e2;
			makeKeyframe(T_world_pred, big, true);
			res.status = FrameStatus::Reinit;
			res.T_kf_curr.setIdentity();
			m_lost = 0;
			m_velocity.setIdentity();
		}
		return finish(T_world_pred);
	};

	if (m_keyframes.empty())
	{
		if (static_cast<int>(res.stereo) < o.min_stereo) return fail(FrameStatus::FewFeatures);
		res.status = FrameStatus::First;
		makeKeyframe(Eigen::Isometry3d::Identity(), Matrix6d::Zero(), false);
		m_lost = 0;
		return finish(Eigen::Isometry3d::Identity());
	}
	if (static_cast<int>(res.stereo) < o.min_stereo) return fail(FrameStatus::FewFeatures);

	// ---- matching to the keyframe inside predicted windows ----------------------
	auto t0 = Clock::now();
	const TKeyframe& kf = m_keyframes.back();
	const Eigen::Isometry3d T_curr_kf_pred = T_world_pred.inverse() * kf.T_world_kf;
	MeasGrid grid;
	grid.build(fr.meas, left8.cols, left8.rows);
	std::vector<int> matchOf(kf.meas.size(), -1), distOf(kf.meas.size(), 999);
	auto matchWithin = [&](double radius) {
		std::vector<int> bestKf(fr.meas.size(), -1), bestD(fr.meas.size(), 999);
		const double r2 = radius * radius;
		for (size_t j = 0; j < kf.meas.size(); j++)
		{
			matchOf[j] = -1;
			const Eigen::Vector3d p = T_curr_kf_pred * kf.meas[j].P;
			if (p.z() < 0.1) continue;
			const double u = calib.fx * p.x() / p.z() + calib.cx, v = calib.fy * p.y() / p.z() + calib.cy;
			const int c0 = std::max(0, static_cast<int>((u - radius) / MeasGrid::kCell));
			const int c1 = std::min(grid.cols - 1, static_cast<int>((u + radius) / MeasGrid::kCell));
			const int r0 = std::max(0, static_cast<int>((v - radius) / MeasGrid::kCell));
			const int r1 = std::min(grid.rows - 1, static_cast<int>((v + radius) / MeasGrid::kCell));
			int b1 = 999, b2 = 999, bi = -1;
			for (int rr = r0; rr <= r1; rr++)
				for (int cc = c0; cc <= c1; cc++)
					for (int i : grid.cells[rr * grid.cols + cc])
					{
						const auto& m = fr.meas[i];
						const double du = m.uL - u, dv = m.v - v;
						if (du * du + dv * dv > r2) continue;
						const int d = features::hamming(kf.meas[j].desc, m.desc);
						if (d < b1)
						{
							b2 = b1;
							b1 = d;
							bi = i;
						}
						else if (d < b2)
							b2 = d;
					}
			if (bi < 0 || b1 > o.max_hamming || (b2 < 999 && b1 >= o.match_ratio * b2)) continue;
			// One keyframe landmark per current measurement: keep the closest descriptor.
			if (b1 < bestD[bi])
			{
				if (bestKf[bi] >= 0) matchOf[bestKf[bi]] = -1;
				bestD[bi] = b1;
				bestKf[bi] = static_cast<int>(j);
				matchOf[j] = bi;
				distOf[j] = b1;
			}
		}
		return static_cast<int>(std::count_if(matchOf.begin(), matchOf.end(), [](int i) { return i >= 0; }));
	};
	int nMatch = matchWithin(m_lost > 0 ? o.search_radius_lost_px : o.search_radius_px);
	if (nMatch < o.min_matches && m_lost == 0) nMatch = matchWithin(o.search_radius_lost_px);

	// Sub-pixel refinement: where is the keyframe's patch in this image?
	std::vector<geometry::TStereoCorrespondence> corr;
	corr.reserve(nMatch);
	const int ph = features::kPatchSize / 2;
	for (size_t j = 0; j < kf.meas.size(); j++)
	{
		if (matchOf[j] < 0) continue;
		const auto& m = fr.meas[matchOf[j]];
		int x = static_cast<int>(m.uL), y = static_cast<int>(m.v);
		const auto inside = [&](int xx, int yy) {
			return xx - ph - 1 >= 0 && yy - ph - 1 >= 0 && xx + ph + 1 < left8.cols && yy + ph + 1 < left8.rows;
		};
		float c[3][3];
		bool peak = false;
		for (int step = 0; step <= o.refine_radius && inside(x, y); step++)
		{
			// All nine scores first, then the arg-max: comparing against the
			// centre before it is computed read an uninitialised value (the
			// run-to-run nondeterminism found with valgrind).
			for (int dy = -1; dy <= 1; dy++)
				for (int dx = -1; dx <= 1; dx++)
					c[dy + 1][dx + 1] = patchZncc(kf.meas[j].patch, fr.left, x + dx, y + dy);
			int bx = 0, by = 0;
			for (int dy = -1; dy <= 1; dy++)
				for (int dx = -1; dx <= 1; dx++)
					if (c[dy + 1][dx + 1] > c[by + 1][bx + 1]) bx = dx, by = dy;
			if (bx == 0 && by == 0)
			{
				peak = true;
				break;
			}
			if (step == o.refine_radius) break;
			x += bx;
			y += by;
		}
		if (!peak || c[1][1] < o.refine_min_zncc) continue;
		float ox = features::parabolaPeak(c[1][0], c[1][1], c[1][2]);
		float oy = features::parabolaPeak(c[0][1], c[1][1], c[2][1]);
		{
			// The parabola locks towards integer pixels; Gauss-Newton on the
			// interpolated image does not (features::refinePatch2D).
			float xr, yr;
			if (features::refinePatch2D(
					kf.meas[j].patch.data(), features::kPatchSize, fr.left, x + ox, y + oy,
					o.refine_iterations, xr, yr))
			{
				ox = xr - x;
				oy = yr - y;
			}
		}
		geometry::TStereoCorrespondence k;
		k.P_ref = kf.meas[j].P;
		k.cov_ref = kf.meas[j].cov;
		// The disparity measured at the corner carries over to the refined position.
		const double du = x + ox - m.uL;
		k.z_curr = Eigen::Vector3d(x + ox, y + oy, m.uR + du);
		if (!calib.triangulate(k.z_curr.x(), k.z_curr.y(), k.z_curr.z(), k.P_curr)) continue;
		corr.push_back(k);
	}
	if (o.near_min_disparity > 0)
	{
		// Near landmarks only, if there are enough of them (see the option).
		const double fb = calib.fx * calib.baseline;
		std::vector<geometry::TStereoCorrespondence> nearCorr;
		for (const auto& k : corr)
			if (fb / k.P_ref.z() >= o.near_min_disparity) nearCorr.push_back(k);
		if (static_cast<int>(nearCorr.size()) >= o.near_min_matches) corr.swap(nearCorr);
	}
	res.tracked = corr.size();
	res.ms.match = msSince(t0);
	if (static_cast<int>(corr.size()) < o.min_matches) return fail(FrameStatus::FewMatches);

	// ---- RANSAC -------------------------------------------------------------------
	t0 = Clock::now();
	geometry::TRansacOptions ro;
	ro.inlier_threshold_px = o.ransac_threshold_px;
	ro.max_iterations = o.ransac_iterations;
	ro.seed = static_cast<uint32_t>(res.frame * 2654435761u + 1);
	// The motion model's prediction competes with the random minimal sets:
	// with only far landmarks (the invariant image outdoors) the inlier count
	// hardly changes along the viewing direction and random sets of noisy
	// far points can settle on a step twice too long (docs/vo.md).
	if (o.ransac_prediction)
	{
		ro.hypotheses.push_back(T_curr_kf_pred);
		// The prediction spans every frame since the last tracked one.
		ro.prior_sigma_m = o.ransac_prior_sigma_m * (1 + m_lost);
	}
	ro.two_view_ba = o.two_view_ba;
	const auto rs = geometry::ransacStereoPose(calib, corr, ro);
	res.inliers = rs.inliers;
	res.ms.ransac = msSince(t0);
	if (!rs.ok || rs.inliers < o.min_inliers) return fail(FrameStatus::FewInliers);

	// ---- non-linear solve ---------------------------------------------------------
	t0 = Clock::now();
	const auto solve = o.two_view_ba ? geometry::solveStereoPoseTwoView : geometry::solveStereoPose;
	geometry::TPoseSolverOptions so;
	so.sigma_px = o.sigma_px;
	so.huber_k = o.huber_k;
	auto sol = solve(calib, corr, rs.inlier, rs.T_curr_ref, so);
	if (sol.ok)
	{
		// Re-select inliers at the refined pose (RANSAC's minimal-set pose is
		// coarse) and solve once more on them.
		std::vector<uint8_t> in(corr.size(), 0);
		int n = 0;
		for (size_t i = 0; i < corr.size(); i++)
		{
			Eigen::Vector3d r;
			in[i] = geometry::stereoResidual(calib, sol.T_curr_ref, corr[i].P_ref, corr[i].z_curr, r) &&
					r.norm() < o.ransac_threshold_px;
			n += in[i];
		}
		if (n >= o.min_inliers)
		{
			const auto sol2 = solve(calib, corr, in, sol.T_curr_ref, so);
			if (sol2.ok)
			{
				sol = sol2;
				res.inliers = n;
			}
		}
	}
	res.ms.solve = msSince(t0);
	if (!sol.ok) return fail(FrameStatus::SolverFailed);

	const Eigen::Isometry3d T_kf_curr = sol.T_curr_ref.inverse();
	const Eigen::Isometry3d T_world_curr = kf.T_world_kf * T_kf_curr;
	const Eigen::Isometry3d step = m_T_world_prev.inverse() * T_world_curr;
	if (step.translation().norm() > o.max_step_translation * (1 + m_lost) ||
		rotationDeg(step) > o.max_step_rotation_deg * (1 + m_lost))
		return fail(FrameStatus::WildMotion);

	res.status = FrameStatus::Ok;
	res.rms_px = sol.rms_px;
	res.T_kf_curr = T_kf_curr;
	res.cov_kf_curr = sol.cov_T_ref_curr;
	// The constant-velocity model: per-frame motion, spread over any gap.
	if (m_lost == 0)
		m_velocity = step;
	else
		m_velocity = V;
	m_lost = 0;

	const double frac = kf.meas.empty() ? 0.0 : double(res.inliers) / kf.meas.size();
	if (T_kf_curr.translation().norm() > o.kf_translation || rotationDeg(T_kf_curr) > o.kf_rotation_deg ||
		frac < o.kf_min_tracked_fraction || static_cast<int>(res.inliers) < o.kf_min_inliers)
		makeKeyframe(T_world_curr, sol.cov_T_ref_curr, false);
	return finish(T_world_curr);
}

}  // namespace shadyloc::vo
