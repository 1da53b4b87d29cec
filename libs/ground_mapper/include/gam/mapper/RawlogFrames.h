// Ground-aware mapping for MRPT
// Streams the "frames" of a rawlog in either format (CActionCollection +
// CSensoryFrame, or bare observations with CObservationOdometry): every
// CObservation3DRangeScan / CObservation2DRangeScan with the robot pose at
// which it was taken.
#pragma once

#include <mrpt/io/CFileGZInputStream.h>
#include <mrpt/obs/CObservation.h>
#include <mrpt/poses/CPose3D.h>

#include <deque>
#include <memory>
#include <string>

namespace gam::mapper
{
struct Frame
{
	size_t index = 0;                ///< 0-based frame number
	size_t entry = 0;                ///< rawlog entry (object) it came from
	mrpt::poses::CPose3D robotPose;  ///< from odometry; identity if none so far
	bool hasOdometry = false;
	mrpt::obs::CObservation::Ptr obs;  ///< a 3D or 2D range scan (loaded)
};

/** Odometry rules:
 *  - observations format: each CObservationOdometry sets the pose (absolute);
 *  - SF format: each CActionCollection's first movement estimation (2D or 3D)
 *    is composed onto the pose; a CObservationOdometry inside a sensory frame
 *    also sets it (absolute);
 *  - before any odometry the robot is at the origin. */
class RawlogFrameReader
{
   public:
	/** Throws std::runtime_error if the file is missing or unreadable. */
	explicit RawlogFrameReader(const std::string& path);
	/** Next frame; false at the end. Throws std::runtime_error on corrupt data. */
	bool next(Frame& f);

	size_t entriesRead() const { return m_entry; }
	size_t skippedObservations() const { return m_skipped; }  ///< other classes, empty scans
	bool sawSensoryFrames() const { return m_sawSF; }
	bool sawObservations() const { return m_sawObs; }
	uint64_t fileSize() const { return m_fileSize; }

   private:
	void handleObservation(const mrpt::obs::CObservation::Ptr& o);
	std::string m_path;
	mrpt::io::CFileGZInputStream m_in;
	size_t m_entry = 0, m_frames = 0, m_skipped = 0;
	uint64_t m_fileSize = 0;
	bool m_sawSF = false, m_sawObs = false, m_eof = false, m_hasOdo = false;
	mrpt::poses::CPose3D m_pose;
	struct Pending
	{
		mrpt::obs::CObservation::Ptr obs;
		size_t entry;
	};
	std::deque<Pending> m_pending;
};

/** True if the observation is a frame the mapper uses (3D or 2D range scan with data). */
bool isUsableScan(const mrpt::obs::CObservation& o);

}  // namespace gam::mapper
