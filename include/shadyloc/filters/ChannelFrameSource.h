/* ShadyLoc — the frames of one stereo camera as its channels see them: the
 * one frame source of the survey, the VO, the localisation, the evaluation
 * and the exporter.
 *
 * Each frame carries its timestamp, calibration and, per requested channel,
 * the channel's image pair: read from a filtered rawlog's derived
 * observations (labelled <camera><suffix>, `shadyloc filter`), or made from
 * the colour pair by the channel's filter (filters/Channel.h). Both kinds may
 * mix (a rawlog filtered for one channel only). The observations of one frame
 * are paired here, and only here: same timestamp, same calibration and image
 * size, one of each; the checks of each camera's own observations are
 * io::StereoFrameChecker's. Errors name the file (or the caller), the object
 * and the frame.
 *
 * ChannelFrameAssembler takes observations one at a time (the public face's
 * process(obs)); ChannelFrameSource feeds it a rawlog.
 */
#pragma once

#include <shadyloc/filters/Channel.h>
#include <shadyloc/geometry/StereoCamera.h>
#include <shadyloc/io/Rawlog.h>
#include <shadyloc/io/StereoFrameSource.h>

#include <mrpt/img/TStereoCamera.h>
#include <mrpt/obs/CObservationStereoImages.h>

#include <opencv2/core/mat.hpp>

#include <functional>
#include <memory>
#include <set>
#include <string>
#include <vector>

namespace shadyloc::filters
{
/** One channel's image pair in a frame. */
struct TChannelPair
{
	std::string label;	//!< the channel ("mono")
	/** Its images (CV_8UC1 for the grey channels); empty until made when
	 * the source defers making them (ChannelFrameAssembler::make). */
	cv::Mat left, right;
	bool read = false;	//!< read from derived observations (else made from the colour pair)
};

/** One frame of a camera, its channels paired. */
struct TChannelFrame
{
	size_t index = 0;  //!< 0-based
	size_t object = 0;	//!< the rawlog object that completed it
	double timestamp = 0;  //!< [s] since the Unix epoch
	std::string camera;	 //!< the colour camera's label (a channel's is camera + suffix)
	geometry::TStereoCalib calib;  //!< the rectified stereo model
	mrpt::img::TStereoCamera stereoCamera;	//!< the calibration as stored
	cv::Size size;	//!< image size [px]
	/** The colour pair as stored (BGR) and its observation; empty/null when
	 * every channel was read (the colour pair is then not looked at). */
	cv::Mat left, right;
	mrpt::obs::CObservationStereoImages::Ptr obs;
	std::vector<TChannelPair> channels;	 //!< in the order asked for
	double ms_convert = 0;	//!< making channels from colour while assembling [ms]
	/** "<source>: frame <i> (camera '<label>'): " for messages. */
	std::string where;
};

/** Where each channel's images come from: the inputs of resolveChannelInput
 * (or the public face's choice), one per channel. */
struct TChannelPlan
{
	std::vector<TChannel> channels;
	std::vector<TChannelInput> inputs;	//!< per channel: read (filtered) from sensorLabel, or made from colour
	/** The colour camera; "" = the first stereo label acceptCamera accepts. */
	std::string camera;
	std::function<bool(const std::string&)> acceptCamera;
	/** True if the colour pair is needed: a channel is made from it, or no
	 * channel is asked for (the colour frames themselves). */
	bool needsColour() const;
};

/** Pairs one camera's observations into frames. */
class ChannelFrameAssembler
{
   public:
	/** makeChannels: make the channels from colour while assembling (else
	 * the caller calls make(), e.g. on its own threads). */
	explicit ChannelFrameAssembler(TChannelPlan plan, bool makeChannels = true);

	/** Offers one stereo observation; true when it completes a frame (then
	 * in f). Observations of labels the plan does not read give false.
	 * `where` names the source and object ("'run.rawlog': object #12").
	 * Throws io::RawlogError naming them and the frame on a second
	 * observation of a label before the frame is complete (channels that do
	 * not pair up), observations of one frame with different timestamps,
	 * calibrations or image sizes, or any check of io::StereoFrameChecker. */
	bool add(const mrpt::obs::CObservationStereoImages::Ptr& obs, size_t object, const std::string& where, TChannelFrame& f);
	/** At the end of the input: throws if a frame was left incomplete. */
	void finish(const std::string& where) const;
	/** Makes channel i's images from the frame's colour pair if not there
	 * yet. Distinct channels of one frame may be made on distinct threads.
	 * Throws io::RawlogError naming the frame and the channel. */
	void make(TChannelFrame& f, size_t i) const;

	const TChannelPlan& plan() const { return m_plan; }
	size_t frames() const { return m_frames; }	//!< frames completed so far
	/** The colour camera ("" until chosen, or when not needed). */
	const std::string& camera() const { return m_labels.empty() ? m_noLabel : m_labels[0]; }
	/** The labels read ("" for a colour camera not chosen yet). */
	const std::vector<std::string>& labels() const { return m_labels; }

   private:
	/** Slot of a label, or -1; may choose the colour camera. */
	int slotOf(const std::string& label);
	void checkPairing(size_t slot, const io::TStereoFrame& got, const std::string& where) const;
	void assemble(size_t object, const std::string& where, TChannelFrame& f);

	TChannelPlan m_plan;
	bool m_make;
	bool m_colourSlot = false;	//!< slot 0 is the colour camera
	std::vector<std::string> m_labels;	//!< per slot
	std::vector<io::StereoFrameChecker> m_checks;  //!< per slot
	std::vector<io::TStereoFrame> m_have;  //!< the pending frame, per slot
	std::vector<bool> m_got;  //!< per slot: in m_have
	size_t m_frames = 0;
	std::string m_noLabel;
};

struct TChannelFrameSourceOptions
{
	std::string camera;	 //!< the colour camera ("" = the first stereo label that is not a derived channel)
	bool makeChannels = true;  //!< see ChannelFrameAssembler
};

/** Objects as they arrive from elsewhere than a rawlog (a live camera):
 * `next` gives one per call, nullptr at the end; `name` names it in
 * messages. */
struct TObjectFeed
{
	std::function<mrpt::serialization::CSerializable::Ptr()> next;
	std::string name;
};

/** The frames of a rawlog's (or a feed's) camera, its channels paired. */
class ChannelFrameSource
{
   public:
	/** A feed's colour frames, every channel made from them (a feed has
	 * no filtered channels); camera "" = its first stereo label. */
	ChannelFrameSource(TObjectFeed feed, const std::vector<TChannel>& channels, const TChannelFrameSourceOptions& o = {});
	/** Opens the rawlog and finds where each channel comes from
	 * (resolveChannelInput). Throws io::RawlogError naming the file if it
	 * is missing, or if a channel must be made from colour and the rawlog
	 * has no colour stereo camera. No channels: the colour frames only. */
	ChannelFrameSource(
		const std::string& rawlog, const std::vector<TChannel>& channels, const TChannelFrameSourceOptions& o = {});

	/** The next frame; false at the end. Throws as ChannelFrameAssembler::add,
	 * or on a rawlog that ends inside a frame. */
	bool next(TChannelFrame& f);
	void make(TChannelFrame& f, size_t i) const { m_assembler.make(f, i); }

	/** Where channel i's images come from. */
	const TChannelInput& input(size_t i) const { return m_assembler.plan().inputs.at(i); }
	const std::vector<TChannel>& channels() const { return m_assembler.plan().channels; }
	/** "read from 'CAMERA_inv'" or "made from the colour camera 'CAMERA'". */
	std::string describeInput(size_t i) const;
	size_t frames() const { return m_assembler.frames(); }
	/** Share of the rawlog read (0 for a feed). */
	double progress() const { return m_reader ? m_reader->progress() : 0.0; }
	/** The rawlog, or the feed's name. */
	const std::string& path() const { return m_reader ? m_reader->path() : m_feed.name; }
	/** "'<path>': no stereo observations labelled ... (other labels: ...)". */
	std::string noFramesMessage() const;

   private:
	/** The next object of the rawlog or feed; nullptr at the end. */
	mrpt::serialization::CSerializable::Ptr nextObject();
	size_t objectIndex() const { return m_reader ? m_reader->index() : m_objects - 1; }

	std::unique_ptr<io::RawlogReader> m_reader;	 //!< null for a feed
	TObjectFeed m_feed;
	size_t m_objects = 0;  //!< objects taken from the feed
	ChannelFrameAssembler m_assembler;
	std::vector<mrpt::obs::CObservation::Ptr> m_pending;  //!< rest of the current sensory frame
	std::set<std::string> m_otherLabels;
	bool m_ended = false;
};

/** The plan for reading `channels` from a rawlog (resolveChannelInput per
 * channel, one camera for all). Throws io::RawlogError naming the file. */
TChannelPlan planChannels(const std::string& rawlog, const std::vector<TChannel>& channels, const std::string& camera);

}  // namespace shadyloc::filters
