/* ShadyLoc — the oracle bound of a localisation run: for every live frame
 * with ground truth, whether a single-shot solve of each localiser against
 * the map finds a true fix when its prediction is the truth (a tight prior:
 * 0.1 m, 1 deg; the keyframe nearest the true pose; the localiser's own
 * search, solve and acceptance with the track taken as confirmed). What the
 * system's tracking, confirmation and relocalisation lose shows as the gap
 * between its true coverage and this bound; what the images lose, as the
 * bound's distance from 100 %. Evaluation only: the truth never reaches the
 * system. */
#pragma once

#include <shadyloc/io/Trajectory.h>
#include <shadyloc/localisation/LocalisationSystem.h>

#include <cstdint>
#include <memory>
#include <vector>

namespace shadyloc::localisation
{
struct TOracleOptions
{
	double sigma_m = 0.1, sigma_deg = 1.0;	//!< the prior around the truth [m], [deg]
	double max_dt_s = 0.01;	 //!< ground truth within this of the frame's stamp [s]
	double true_max_m = 0.5, true_max_deg = 2.0;  //!< a true fix (TEvalOptions) [m], [deg]
	double kf_max_distance_m = 5.0, kf_max_angle_deg = 30.0;  //!< the nearest keyframe by truth, at most [m], [deg]
};

class Oracle
{
   public:
	/** Localisers as the system's (same channels, options, map); `gt` in the
	 * map's ground-truth frame. */
	Oracle(const LocalisationSystem& sys, const io::Trajectory& gt, const TOracleOptions& o = {});
	~Oracle();

	/** Fills u.oracle (per localiser, policy order: 1 a true single-shot fix,
	 * 0 none, -1 no truth or no keyframe near it) from the frame's
	 * measurements (the system's channel order). */
	void probe(TLocalisationUpdate& u, const std::vector<features::TStereoFrame>& meas, const geometry::TStereoCalib& calib);

   private:
	struct TImpl;
	std::unique_ptr<TImpl> m;
};

}  // namespace shadyloc::localisation
