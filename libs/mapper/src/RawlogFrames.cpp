#include <gam/mapper/Errors.h>
#include <gam/mapper/RawlogFrames.h>
#include <mrpt/img/CImage.h>
#include <mrpt/obs/CActionCollection.h>
#include <mrpt/obs/CObservation2DRangeScan.h>
#include <mrpt/obs/CObservation3DRangeScan.h>
#include <mrpt/obs/CObservationOdometry.h>
#include <mrpt/obs/CRawlog.h>
#include <mrpt/obs/CSensoryFrame.h>
#include <mrpt/serialization/CArchive.h>
#include <mrpt/system/filesystem.h>

#include <cstdlib>
#include <fstream>
#include <new>
#include <stdexcept>

// MRPT 2.5's aligned_allocator_cpp11 (CMatrixDynamic, range images, point
// clouds) never checks what mrpt::aligned_malloc() returns: a corrupt rawlog whose
// image or matrix size field asks for terabytes makes it memset a null pointer
// (SIGSEGV inside CObservation3DRangeScan::serializeFrom). This definition
// interposes libmrpt-core's in every program that links ground_mapper (the
// executable's symbol wins), and throws std::bad_alloc instead, so the reader
// reports "cannot read rawlog ... corrupt". Same alignment rule as MRPT's; memory
// from it is released by mrpt::aligned_free() = free(), as MRPT's own.
namespace mrpt
{
void* aligned_malloc(size_t size, size_t alignment)
{
	// No single MRPT buffer of a sane rawlog comes near this (a 16-bit 640x480
	// range image is 600 KiB): larger means a corrupt size field.
	constexpr size_t kLimit = size_t(1) << 30;
	if (alignment == 0 || size > kLimit) throw std::bad_alloc();
	if (size % alignment != 0) size = (size / alignment + 1) * alignment;
	void* p = std::aligned_alloc(alignment, size);
	if (!p && size) throw std::bad_alloc();
	return p;
}
}  // namespace mrpt

namespace gam::mapper
{
using namespace mrpt::obs;

bool isUsableScan(const CObservation& o)
{
	if (const auto* s3 = dynamic_cast<const CObservation3DRangeScan*>(&o))
		return (s3->hasRangeImage && s3->rangeImage.cols() > 0 && s3->rangeImage.rows() > 0) ||
			(s3->hasPoints3D && !s3->points3D_x.empty());
	if (const auto* s2 = dynamic_cast<const CObservation2DRangeScan*>(&o)) return s2->getScanSize() > 0;
	return false;
}

RawlogFrameReader::RawlogFrameReader(const std::string& path) : m_path(path)
{
	if (!mrpt::system::fileExists(path)) throw std::runtime_error("rawlog file not found: " + path);
	{
		std::ifstream probe(path, std::ios::binary | std::ios::ate);
		if (!probe) throw std::runtime_error("cannot read rawlog file: " + path);
		m_fileSize = uint64_t(probe.tellg());
	}
	if (!m_in.open(path)) throw std::runtime_error("cannot open rawlog file: " + path);
	// Externally stored images / range data live in <name>_Images/.
	const std::string imgDir = CRawlog::detectImagesDirectory(path);
	if (mrpt::system::directoryExists(imgDir)) mrpt::img::CImage::setImagesPathBase(imgDir);
}

void RawlogFrameReader::handleObservation(const CObservation::Ptr& o)
{
	if (!o) return;
	if (auto odo = std::dynamic_pointer_cast<CObservationOdometry>(o))
	{
		m_pose = mrpt::poses::CPose3D(odo->odometry);
		m_hasOdo = true;
		return;
	}
	if (IS_CLASS(*o, CObservation3DRangeScan) || IS_CLASS(*o, CObservation2DRangeScan))
	{
		m_pending.push_back({o, m_entry});
		return;
	}
	m_skipped++;
}

bool RawlogFrameReader::next(Frame& f)
{
	while (true)
	{
		while (!m_pending.empty())
		{
			Pending p = m_pending.front();
			m_pending.pop_front();
			try
			{
				p.obs->load();
			}
			catch (const std::exception& e)
			{
				throw std::runtime_error(
					"rawlog entry " + std::to_string(p.entry) + ": cannot load external data of " +
					p.obs->GetRuntimeClass()->className + " (" + conciseError(e.what()) + ")");
			}
			if (!isUsableScan(*p.obs))
			{
				m_skipped++;
				continue;
			}
			f.index = m_frames++;
			f.entry = p.entry;
			f.robotPose = m_pose;
			f.hasOdometry = m_hasOdo;
			f.obs = p.obs;
			return true;
		}
		if (m_eof) return false;

		mrpt::serialization::CSerializable::Ptr obj;
		try
		{
			auto ar = mrpt::serialization::archiveFrom(m_in);
			obj = ar.ReadObject();
		}
		catch (const mrpt::serialization::CExceptionEOF&)
		{
			// zlib stops returning data on a corrupt deflate stream too: only the
			// real end of the file is a clean end.
			if (!m_in.checkEOF())
				throw std::runtime_error(
					"cannot read rawlog " + m_path + " at entry " + std::to_string(m_entry) +
					" (corrupt: the gzip stream cannot be decompressed past this point)");
			m_eof = true;
			continue;
		}
		catch (const std::exception& e)
		{
			const std::string msg = conciseError(e.what());
			throw std::runtime_error(
				"cannot read rawlog " + m_path + " at entry " + std::to_string(m_entry) +
				" (not a rawlog, corrupt, or a class from a plugin that is not loaded): " + msg);
		}
		const size_t thisEntry = m_entry++;
		(void)thisEntry;
		if (!obj) continue;
		if (auto acts = std::dynamic_pointer_cast<CActionCollection>(obj))
		{
			m_sawSF = true;
			mrpt::poses::CPose3D inc;
			if (acts->getFirstMovementEstimationMean(inc))
			{
				m_pose = m_pose + inc;
				m_hasOdo = true;
			}
		}
		else if (auto sf = std::dynamic_pointer_cast<CSensoryFrame>(obj))
		{
			m_sawSF = true;
			// Odometry first, so every scan of the frame gets it.
			for (const auto& o : *sf)
				if (IS_CLASS(*o, CObservationOdometry)) handleObservation(o);
			for (const auto& o : *sf)
				if (!IS_CLASS(*o, CObservationOdometry)) handleObservation(o);
		}
		else if (auto o = std::dynamic_pointer_cast<CObservation>(obj))
		{
			m_sawObs = true;
			handleObservation(o);
		}
		else
			m_skipped++;
	}
}

}  // namespace gam::mapper
