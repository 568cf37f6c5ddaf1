/* ShadyLoc — keyframe map types: channel parameters, pose composition. */
#include <shadyloc/map/MapTypes.h>

#include <cmath>
#include <sstream>

namespace shadyloc::map
{
std::string toString(ChannelKind k) { return k == ChannelKind::Mono ? "mono" : "invariant"; }

TChannelParams TChannelParams::From(
	const std::string& label, ChannelKind kind, const features::TStereoFeatureOptions& fo,
	const image::InvariantParams& inv, image::ChannelOrder order)
{
	TChannelParams p;
	p.label = label;
	p.kind = kind;
	p.order = order;
	if (kind == ChannelKind::Invariant) p.invariant = inv;
	p.brief_patch_size = fo.brief_patch_size;
	p.brief_seed = fo.brief_seed;
	p.presmooth_sigma = fo.presmooth_sigma;
	p.sigma_px = fo.sigma_px;
	return p;
}

std::string TChannelParams::asString() const
{
	std::ostringstream s;
	s << "'" << label << "': " << toString(kind);
	if (kind == ChannelKind::Invariant)
		s << " (" << invariant.asString() << ")";
	else
		s << " (order " << image::toString(order) << ")";
	s << ", BRIEF patch " << brief_patch_size << " px seed " << brief_seed << ", presmooth "
	  << presmooth_sigma << " px";
	return s.str();
}

std::string TChannelParams::differences(const TChannelParams& o) const
{
	std::vector<std::string> d;
	if (kind != o.kind) d.push_back("channel kind");
	if (kind == ChannelKind::Mono && o.kind == ChannelKind::Mono && order != o.order) d.push_back("colour order");
	if (kind == ChannelKind::Invariant && o.kind == ChannelKind::Invariant && !invariant.sameImageAs(o.invariant))
		d.push_back("invariant transform / 8-bit mapping");
	if (brief_patch_size != o.brief_patch_size) d.push_back("BRIEF patch size");
	if (brief_seed != o.brief_seed) d.push_back("BRIEF pattern seed");
	if (std::abs(presmooth_sigma - o.presmooth_sigma) > 1e-9) d.push_back("pre-smoothing");
	std::string out;
	for (const auto& x : d) out += (out.empty() ? "" : ", ") + x;
	return out;
}

bool TChannelParams::operator==(const TChannelParams& o) const
{
	return label == o.label && differences(o).empty() && sigma_px == o.sigma_px &&
		   (kind != ChannelKind::Invariant ||
			(invariant.alpha == o.invariant.alpha && invariant.beta == o.invariant.beta &&
			 invariant.order == o.invariant.order && invariant.linearisation == o.invariant.linearisation &&
			 invariant.gamma == o.invariant.gamma && invariant.scale == o.invariant.scale &&
			 invariant.offset == o.invariant.offset));
}

void composeWithCovariance(
	const Eigen::Isometry3d& T_ab, const geometry::Matrix6d& cov_ab, const Eigen::Isometry3d& T_bc,
	const geometry::Matrix6d& cov_bc, Eigen::Isometry3d& T_ac, geometry::Matrix6d& cov_ac)
{
	// exp(a) T_ab exp(b) T_bc = exp(a) exp(Ad(T_ab) b) T_ab T_bc ~ exp(a + Ad(T_ab) b) T_ac
	const geometry::Matrix6d A = geometry::adjoint(T_ab);
	const geometry::Matrix6d c = cov_ab + A * cov_bc * A.transpose();
	T_ac = T_ab * T_bc;
	cov_ac = 0.5 * (c + c.transpose());
}

}  // namespace shadyloc::map
