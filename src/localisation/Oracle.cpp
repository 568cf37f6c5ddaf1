/* ShadyLoc — the oracle bound of a localisation run (see Oracle.h). */
#include <shadyloc/localisation/Oracle.h>
#include <shadyloc/core/Units.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace shadyloc::localisation
{
namespace
{
using core::kDeg;

double axesAngleDeg(const Eigen::Isometry3d& A, const Eigen::Isometry3d& B)
{
	return std::acos(std::clamp(A.linear().col(2).dot(B.linear().col(2)), -1.0, 1.0)) / kDeg;
}
}  // namespace

struct Oracle::TImpl
{
	const LocalisationSystem& sys;
	io::Trajectory gt;	//!< sorted by time
	TOracleOptions o;
	struct TProbe
	{
		size_t channel;	 //!< index into the system's channels (the measurements' order)
		std::unique_ptr<StereoLocaliser> localiser;
	};
	std::vector<TProbe> probes;	 //!< policy order

	TImpl(const LocalisationSystem& s, const io::Trajectory& g, const TOracleOptions& opts) : sys(s), gt(g), o(opts)
	{
		io::sortByTime(gt);
		const auto labels = sys.channelLabels();
		for (const auto& l : sys.options().localisers)
		{
			const auto it = std::find(labels.begin(), labels.end(), l);
			const StereoLocaliser* loc = sys.localiser(l);
			if (it == labels.end() || !loc) continue;
			probes.push_back({static_cast<size_t>(it - labels.begin()),
							  std::make_unique<StereoLocaliser>(sys.map(), l, loc->options())});
		}
	}

	/** The true live pose at `stamp`, or nullptr. */
	const Eigen::Isometry3d* truthAt(double stamp) const
	{
		const auto it = std::lower_bound(
			gt.begin(), gt.end(), stamp, [](const io::TStampedPose& p, double t) { return p.t < t; });
		const io::TStampedPose* best = nullptr;
		for (auto c : {it, it == gt.begin() ? it : std::prev(it)})
			if (c != gt.end() && std::abs(c->t - stamp) <= o.max_dt_s &&
				(!best || std::abs(c->t - stamp) < std::abs(best->t - stamp)))
				best = &*c;
		return best ? &best->T : nullptr;
	}

	/** The map keyframe nearest the true pose (by ground truth), or -1. */
	int nearestKeyframe(const Eigen::Isometry3d& T) const
	{
		int best = -1;
		double bestD = std::numeric_limits<double>::infinity();
		for (const auto& k : sys.map().keyframes())
		{
			if (!k.T_gt_kf) continue;
			const double d = (k.T_gt_kf->translation() - T.translation()).norm();
			if (d < bestD && d <= o.kf_max_distance_m && axesAngleDeg(*k.T_gt_kf, T) <= o.kf_max_angle_deg)
			{
				bestD = d;
				best = static_cast<int>(k.id);
			}
		}
		return best;
	}
};

Oracle::Oracle(const LocalisationSystem& sys, const io::Trajectory& gt, const TOracleOptions& o)
	: m(std::make_unique<TImpl>(sys, gt, o))
{
}

Oracle::~Oracle() = default;

void Oracle::probe(TLocalisationUpdate& u, const std::vector<features::TStereoFrame>& meas, const geometry::TStereoCalib& calib)
{
	u.oracle.assign(m->probes.size(), -1);
	const Eigen::Isometry3d* T = m->truthAt(u.timestamp);
	if (!T) return;
	const int kf = m->nearestKeyframe(*T);
	if (kf < 0) return;
	const Eigen::Isometry3d T_gt_kf = *m->sys.map().keyframe(static_cast<uint32_t>(kf)).T_gt_kf;
	TLocaliserInput in;
	in.frame = u.frame;
	in.timestamp = u.timestamp;
	in.calib = calib;
	in.prediction.valid = true;
	in.prediction.kf = static_cast<uint32_t>(kf);
	in.prediction.T_kf_live = T_gt_kf.inverse() * *T;
	const double sr = m->o.sigma_deg * kDeg;
	in.prediction.cov.diagonal() << Eigen::Vector3d::Constant(m->o.sigma_m * m->o.sigma_m), Eigen::Vector3d::Constant(sr * sr);
	in.track_confirmed = true;	// one shot: acceptance without confirmation
	for (size_t p = 0; p < m->probes.size(); p++)
	{
		auto& probe = m->probes[p];
		probe.localiser->reset();
		in.meas = &meas[probe.channel];
		const TLocaliserResult r = probe.localiser->localise(in);
		if (!r.accepted())
		{
			u.oracle[p] = 0;
			continue;
		}
		const auto& K = m->sys.map().keyframe(r.kf_id);
		if (!K.T_gt_kf)
		{
			u.oracle[p] = 0;
			continue;
		}
		const Eigen::Isometry3d truth = K.T_gt_kf->inverse() * *T;
		const double em = (truth.translation() - r.T_kf_live.translation()).norm();
		const double ed = Eigen::AngleAxisd(truth.linear().transpose() * r.T_kf_live.linear()).angle() / kDeg;
		u.oracle[p] = em <= m->o.true_max_m && ed <= m->o.true_max_deg ? 1 : 0;
	}
}

}  // namespace shadyloc::localisation
