/* ShadyLoc — evaluation of a localisation run (docs/localisation.md). */
#include <shadyloc/core/Units.h>
#include <shadyloc/eval/BlindEpisodes.h>
#include <shadyloc/eval/Evaluation.h>
#include <shadyloc/localisation/FixAcceptance.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>
#include <unordered_map>

namespace shadyloc::eval
{
using localisation::TLocalisationUpdate;
using localisation::TLocaliserResult;

namespace
{
using core::kDeg;

double axesAngleDeg(const Eigen::Isometry3d& A, const Eigen::Isometry3d& B)
{
	return std::acos(std::clamp(A.linear().col(2).dot(B.linear().col(2)), -1.0, 1.0)) / kDeg;
}

/** Hash grid over 3D points: the candidates within a radius. */
class PointGrid
{
   public:
	PointGrid(double cell) : m_cell(cell) {}
	void add(const Eigen::Vector3d& p, size_t id) { m_cells[key(p)].push_back(id); }
	template <typename F>
	void near(const Eigen::Vector3d& p, F&& f) const
	{
		const auto c = cellOf(p);
		for (int dx = -1; dx <= 1; dx++)
			for (int dy = -1; dy <= 1; dy++)
				for (int dz = -1; dz <= 1; dz++)
				{
					const auto it = m_cells.find(key3(c[0] + dx, c[1] + dy, c[2] + dz));
					if (it == m_cells.end()) continue;
					for (const size_t id : it->second) f(id);
				}
	}

   private:
	std::array<long long, 3> cellOf(const Eigen::Vector3d& p) const
	{
		return {static_cast<long long>(std::floor(p.x() / m_cell)), static_cast<long long>(std::floor(p.y() / m_cell)),
				static_cast<long long>(std::floor(p.z() / m_cell))};
	}
	static uint64_t key3(long long x, long long y, long long z)
	{
		return (static_cast<uint64_t>(x) * 73856093ull) ^ (static_cast<uint64_t>(y) * 19349663ull) ^
			   (static_cast<uint64_t>(z) * 83492791ull);
	}
	uint64_t key(const Eigen::Vector3d& p) const
	{
		const auto c = cellOf(p);
		return key3(c[0], c[1], c[2]);
	}
	double m_cell;
	std::unordered_map<uint64_t, std::vector<size_t>> m_cells;
};

/** Truth of a fix relative to keyframe kf, given the live ground-truth pose. */
FixTruth judge(
	const CKeyframeMap& map, uint32_t kf, const Eigen::Isometry3d& T_kf_live, const Eigen::Isometry3d& T_gt_live,
	const TEvalOptions& o, double* errM = nullptr, double* errDeg = nullptr)
{
	const auto& k = map.keyframe(kf);
	if (!k.T_gt_kf) return FixTruth::None;
	const Eigen::Isometry3d truth = k.T_gt_kf->inverse() * T_gt_live;
	const double em = (truth.translation() - T_kf_live.translation()).norm();
	const double ed = Eigen::AngleAxisd(truth.linear().transpose() * T_kf_live.linear()).angle() / kDeg;
	if (errM) *errM = em;
	if (errDeg) *errDeg = ed;
	return em <= o.true_max_m && ed <= o.true_max_deg ? FixTruth::True : FixTruth::False;
}
/** The solve log's figures of localiser c's solve: error and NEES against the truth. */
void solveError(
	const CKeyframeMap& map, const TLocaliserResult& r, const Eigen::Isometry3d& T_gt_live, const TEvalOptions& o,
	TFrameEval& f, size_t c)
{
	const auto& k = map.keyframe(r.kf_id);
	if (!k.T_gt_kf) return;
	judge(map, r.kf_id, r.T_kf_live, T_gt_live, o, &f.solve_err_m[c], &f.solve_err_deg[c]);
	const Eigen::Isometry3d truth = k.T_gt_kf->inverse() * T_gt_live;
	f.solve_nees[c] = localisation::mahalanobis2(geometry::localLeft(r.T_kf_live, truth), r.cov);
}

}  // namespace

TBlindProbability blindProbability(const std::vector<double>& lengths, const TEvalOptions& o)
{
	TBlindProbability r;
	r.episodes = lengths.size();
	r.reaching = static_cast<size_t>(
		std::count_if(lengths.begin(), lengths.end(), [&](double l) { return l >= o.blind_long_m; }));
	if (lengths.empty()) return r;
	r.p = static_cast<double>(r.reaching) / static_cast<double>(lengths.size());
	const TProportionInterval cp = clopperPearson(r.reaching, r.episodes, 0.95);
	r.exact_lo = cp.lo;
	r.exact_hi = cp.hi;
	// Percentile bootstrap over episodes (seeded: the summary is repeatable).
	std::mt19937 rng(o.bootstrap_seed);
	std::uniform_int_distribution<size_t> pick(0, lengths.size() - 1);
	std::vector<double> ps;
	ps.reserve(o.bootstrap_samples);
	for (int b = 0; b < o.bootstrap_samples; b++)
	{
		size_t k = 0;
		for (size_t j = 0; j < lengths.size(); j++) k += lengths[pick(rng)] >= o.blind_long_m;
		ps.push_back(static_cast<double>(k) / lengths.size());
	}
	std::sort(ps.begin(), ps.end());
	r.lo = ps[static_cast<size_t>(0.025 * (ps.size() - 1))];
	r.hi = ps[static_cast<size_t>(0.975 * (ps.size() - 1))];
	return r;
}

namespace
{
/** The live run's ground truth: sorted, and the index of each frame's pose
 * in it (-1: none within assoc_dt_s). */
struct TLiveTruth
{
	io::Trajectory poses;
	std::vector<int> of;
};

/** Associates the frames with the ground truth (throwing when too few do)
 * and measures the distance travelled along it (VO's across frames without it). */
TLiveTruth associateTruth(TEvaluation& ev, const Updates& ups, const io::Trajectory& gt, const TEvalOptions& o)
{
	const size_t n = ups.size();
	TLiveTruth t{gt, std::vector<int>(n, -1)};
	io::Trajectory est;
	for (const auto& u : ups) est.push_back({u.timestamp, Eigen::Isometry3d::Identity()});
	io::sortByTime(t.poses);  // associate() refers to the sorted copy
	for (const auto& p : io::associate(t.poses, est, o.assoc_dt_s)) t.of[p.second] = static_cast<int>(p.first);
	ev.associated = static_cast<size_t>(std::count_if(t.of.begin(), t.of.end(), [](int i) { return i >= 0; }));
	if (n > 0 && ev.associated < o.min_associated * n)
		throw std::runtime_error(
			"ground truth: only " + std::to_string(ev.associated) + " of " + std::to_string(n) +
			" live frames have a pose within " + std::to_string(o.assoc_dt_s) + " s (at least " +
			std::to_string(static_cast<int>(o.min_associated * 100)) + " % needed)");
	double d = 0;
	for (size_t i = 0; i < n; i++)
	{
		if (i > 0)
		{
			if (t.of[i] >= 0 && t.of[i - 1] >= 0)
				d += (t.poses[t.of[i]].T.translation() - t.poses[t.of[i - 1]].T.translation()).norm();
			else
				d += ups[i].distance_m - ups[i - 1].distance_m;
		}
		ev.frames[i].distance_m = d;
		ev.frames[i].has_truth = t.of[i] >= 0;
	}
	return t;
}

/** in_map from both runs' ground truth: a keyframe's within in_map_m and in_map_deg. */
void inMapFromTruth(TEvaluation& ev, const CKeyframeMap& map, const TLiveTruth& t, const TEvalOptions& o)
{
	for (const auto& k : map.keyframes())
		if (!k.T_gt_kf)
			throw std::runtime_error(
				"ground truth: the map's keyframes carry no ground truth (survey it with --gt): fixes cannot be checked");
	PointGrid grid(o.in_map_m);
	for (const auto& k : map.keyframes()) grid.add(k.T_gt_kf->translation(), k.id);
	for (size_t i = 0; i < ev.frames.size(); i++)
	{
		if (t.of[i] < 0) continue;
		const auto& T = t.poses[t.of[i]].T;
		bool in = false;
		grid.near(T.translation(), [&](size_t id) {
			const auto& K = *map.keyframe(static_cast<uint32_t>(id)).T_gt_kf;
			in |= (K.translation() - T.translation()).norm() <= o.in_map_m && axesAngleDeg(K, T) <= o.in_map_deg;
		});
		ev.frames[i].in_map = in;
	}
}

/** The truth of every localiser's fix and solve, and of the fix used. */
void judgeFixes(TEvaluation& ev, const Updates& ups, const CKeyframeMap& map, const TLiveTruth& t, const TEvalOptions& o)
{
	const size_t nCh = ev.channels.size();
	for (size_t i = 0; i < ups.size(); i++)
	{
		auto& f = ev.frames[i];
		f.channel.assign(nCh, FixTruth::None);
		f.solve_err_m.assign(nCh, -1);
		f.solve_err_deg.assign(nCh, -1);
		f.solve_nees.assign(nCh, -1);
		if (t.of[i] < 0) continue;
		const auto& T = t.poses[t.of[i]].T;
		for (size_t c = 0; c < nCh; c++)
		{
			const auto& r = ups[i].localisers[c];
			if (r.accepted()) f.channel[c] = judge(map, r.kf_id, r.T_kf_live, T, o);
			if (r.solved) solveError(map, r, T, o, f, c);
		}
		if (ups[i].localised()) f.used = judge(map, ups[i].kf_id, ups[i].T_kf_live, T, o, &f.used_err_m, &f.used_err_deg);
	}
}

/** Without ground truth: VO's distance, in_map from the system's own
 * estimate (frames with no known place count as in the map). */
void inMapFromEstimate(TEvaluation& ev, const Updates& ups, const CKeyframeMap& map, const TEvalOptions& o)
{
	map::TNearestQuery q;
	q.max_distance_m = o.in_map_m;
	q.max_angle_deg = o.in_map_deg;
	q.max_results = 1;
	for (size_t i = 0; i < ups.size(); i++)
	{
		auto& f = ev.frames[i];
		f.distance_m = ups[i].distance_m;
		f.channel.assign(ev.channels.size(), FixTruth::None);
		q.same_frame_as = ups[i].placeKnown ? int64_t(ups[i].kf_id) : -1;	// T_map_live is in its keyframe's frame
		f.in_map = !ups[i].placeKnown || !map.nearestKeyframes(ups[i].T_map_live, q).empty();
	}
}

/** The oracle bound, when the run was probed: in-map frames with a true single-shot fix. */
void oracleBound(TEvaluation& ev, const Updates& ups)
{
	ev.oracle = !ups.empty() && !ups.front().oracle.empty();
	if (!ev.oracle) return;
	ev.oracle_in_map.assign(ups.front().oracle.size(), 0);
	for (size_t i = 0; i < ups.size(); i++)
	{
		if (!ev.frames[i].in_map || ups[i].oracle.size() != ev.oracle_in_map.size()) continue;
		bool any = false;
		for (size_t c = 0; c < ev.oracle_in_map.size(); c++)
		{
			ev.oracle_in_map[c] += ups[i].oracle[c] == 1;
			any |= ups[i].oracle[c] == 1;
		}
		ev.oracle_any_in_map += any;
	}
}

/** Localiser r's accepted fix on frame u, into its counts. */
void countChannelFix(TChannelSummary& cs, const TLocalisationUpdate& u, const TLocaliserResult& r, FixTruth truth, bool withGt)
{
	cs.accepted++;
	cs.used += u.used == r.channel;
	if (truth == FixTruth::True)
		cs.true_fixes++;
	else if (truth == FixTruth::False)
		cs.false_fixes++;
	else if (withGt)
		cs.unverifiable++;
}

/** Fixes used (true, false, unverifiable), per localiser, and the coverages. */
void countFixes(TEvaluation& ev, const Updates& ups)
{
	const bool gt = ev.ground_truth;
	for (size_t i = 0; i < ups.size(); i++)
	{
		const auto& u = ups[i];
		const auto& f = ev.frames[i];
		ev.in_map_frames += f.in_map;
		ev.global_searches += u.global_search;
		if (u.localised())
		{
			ev.fixes++;
			ev.fixes_in_map += f.in_map;
			ev.true_fixes += f.used == FixTruth::True;
			ev.true_fixes_in_map += f.used == FixTruth::True && f.in_map;
			ev.false_fixes += f.used == FixTruth::False;
			ev.unverifiable += f.used == FixTruth::None && gt;
		}
		for (size_t c = 0; c < ev.channels.size(); c++)
			if (u.localisers[c].accepted()) countChannelFix(ev.channels[c], u, u.localisers[c], f.channel[c], gt);
	}
	auto ratio = [](size_t a, size_t b) { return b ? static_cast<double>(a) / static_cast<double>(b) : 0.0; };
	ev.coverage_in_map = ratio(ev.fixes_in_map, ev.in_map_frames);
	ev.coverage_all = ratio(ev.fixes, ups.size());
	ev.true_coverage_in_map = ratio(ev.true_fixes_in_map, ev.in_map_frames);
	ev.oracle_any_coverage = ratio(ev.oracle_any_in_map, ev.in_map_frames);
	ev.true_coverage_all = ratio(ev.true_fixes, ups.size());
	ev.false_fix_share = ratio(ev.false_fixes, ev.true_fixes + ev.false_fixes);
}

/** The blind episodes, the distance without a fix and P(an episode reaches blind_long_m). */
void blindSummary(TEvaluation& ev, const Updates& ups, const TEvalOptions& o)
{
	const size_t n = ups.size();
	std::vector<bool> fix(n);
	std::vector<double> dist(n);
	for (size_t i = 0; i < n; i++) fix[i] = ups[i].localised(), dist[i] = ev.frames[i].distance_m;
	ev.episodes = blindEpisodes(fix, dist);
	std::vector<double> between;
	double before = 0;	// a run that starts with a fix has no such episode
	for (const auto& e : ev.episodes)
	{
		ev.blind_m += e.length_m;
		if (e.kind == TBlindEpisode::Between) between.push_back(e.length_m);
		if (e.kind == TBlindEpisode::BeforeFirstFix) before = e.length_m;
	}
	const auto first = std::find(fix.begin(), fix.end(), true);
	ev.first_fix_frame = first == fix.end() ? -1 : static_cast<int>(first - fix.begin());
	ev.before_first_fix_m = ev.first_fix_frame < 0 ? -1 : before;
	ev.total_m = n ? dist[n - 1] - dist[0] : 0;
	ev.blind_m_per_km = ev.total_m > 0 ? 1000 * ev.blind_m / ev.total_m : 0;
	ev.episodes_between = between.size();
	const TBlindProbability bp = blindProbability(between, o);
	ev.episodes_long = bp.reaching;
	ev.p_long = bp.p;
	ev.p_long_lo = bp.lo;
	ev.p_long_hi = bp.hi;
	ev.p_long_exact_lo = bp.exact_lo;
	ev.p_long_exact_hi = bp.exact_hi;
}
}  // namespace

TEvaluation evaluate(const Updates& ups, const CKeyframeMap& map, const io::Trajectory* gt, const TEvalOptions& o)
{
	TEvaluation ev;
	ev.frames.resize(ups.size());
	ev.ground_truth = gt != nullptr;
	if (!ups.empty())
		for (const auto& r : ups.front().localisers) ev.channels.push_back({r.channel});
	if (gt)
	{
		const TLiveTruth truth = associateTruth(ev, ups, *gt, o);
		inMapFromTruth(ev, map, truth, o);
		judgeFixes(ev, ups, map, truth, o);
	}
	else
		inMapFromEstimate(ev, ups, map, o);
	oracleBound(ev, ups);
	countFixes(ev, ups);
	blindSummary(ev, ups, o);
	return ev;
}

}  // namespace shadyloc::eval
