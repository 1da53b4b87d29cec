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

#include <algorithm>
#include <cstdlib>
#include <cstring>
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

// Same kind of problem (found by tests/fuzz/fuzz_rawlog): MRPT's string reader
// resizes the string to the stored uint32 length before reading it, so one
// corrupt length field allocates and zeroes up to 4 GiB. This definition
// (interposing libmrpt-serialization's, same wire format: uint32 length, bytes)
// refuses lengths no rawlog string has.
namespace mrpt::serialization
{
CArchive& operator>>(CArchive& in, std::string& str)
{
	uint32_t n = 0;
	in.ReadBuffer(&n, sizeof(n));
	constexpr uint32_t kLimit = 64u << 20;
	if (n > kLimit)
		throw std::runtime_error("corrupt data: a serialized string of " + std::to_string(n) + " bytes (limit 64 MiB)");
	str.resize(n);
	if (n) in.ReadBuffer(&str[0], n);
	return in;
}
}  // namespace mrpt::serialization

namespace gam::mapper
{
using namespace mrpt::obs;

namespace
{
/** A read-only view of the rawlog stream that can look at the start of the next
 * object before MRPT deserializes it. MRPT 2.5 reads the element count of a
 * CSensoryFrame / CActionCollection and resizes its container to it before reading
 * any element: a corrupt count makes a 1 KB rawlog allocate tens of GB (found by
 * tests/fuzz/fuzz_rawlog). Peeked bytes never exceed the object being read, so the
 * buffer is always consumed by the following ReadObject(). */
class PeekStream : public mrpt::io::CStream
{
   public:
	explicit PeekStream(mrpt::io::CStream& in) : m_in(in) {}
	/** Makes the first n bytes of the rest available in data(); returns how many are. */
	size_t peek(size_t n)
	{
		while (m_buf.size() - m_pos < n)
		{
			uint8_t tmp[256];
			const size_t want = std::min(sizeof(tmp), n - (m_buf.size() - m_pos));
			const size_t got = m_in.Read(tmp, want);
			if (got == 0 || got > want) break;  // EOF or error
			m_buf.insert(m_buf.end(), tmp, tmp + got);
		}
		return m_buf.size() - m_pos;
	}
	const uint8_t* data() const { return m_buf.data() + m_pos; }
	size_t Read(void* buffer, size_t count) override
	{
		auto* out = static_cast<uint8_t*>(buffer);
		const size_t fromBuf = std::min(count, m_buf.size() - m_pos);
		std::copy_n(m_buf.data() + m_pos, fromBuf, out);
		m_pos += fromBuf;
		if (fromBuf == count) return count;
		const size_t got = m_in.Read(out + fromBuf, count - fromBuf);
		return got > count - fromBuf ? fromBuf : fromBuf + got;
	}
	size_t Write(const void*, size_t) override { throw std::logic_error("PeekStream is read-only"); }
	uint64_t Seek(int64_t, mrpt::io::CStream::TSeekOrigin) override
	{
		throw std::logic_error("PeekStream cannot seek");
	}
	uint64_t getTotalBytesCount() const override { return m_in.getTotalBytesCount(); }
	uint64_t getPosition() const override { return m_in.getPosition() - (m_buf.size() - m_pos); }

   private:
	mrpt::io::CStream& m_in;
	std::vector<uint8_t> m_buf;
	size_t m_pos = 0;
};

/** Rejects a CSensoryFrame / CActionCollection whose element count is absurd
 * (MRPT's format: byte 0x80|L, L name bytes, version byte, uint32 count LE). */
void checkContainerCount(PeekStream& ps, const std::string& where)
{
	if (ps.peek(1) < 1 || !(ps.data()[0] & 0x80)) return;
	const size_t L = ps.data()[0] & 0x7F;
	if (ps.peek(1 + L) < 1 + L) return;
	const std::string name(reinterpret_cast<const char*>(ps.data()) + 1, L);
	if (name != "mrpt::obs::CSensoryFrame" && name != "mrpt::obs::CActionCollection") return;
	if (ps.peek(1 + L + 5) < 1 + L + 5) return;
	const uint8_t* c = ps.data() + 1 + L + 1;
	const uint32_t n = uint32_t(c[0]) | uint32_t(c[1]) << 8 | uint32_t(c[2]) << 16 | uint32_t(c[3]) << 24;
	constexpr uint32_t kMaxElements = 100000;
	if (n > kMaxElements)
		throw std::runtime_error(
			where + " (corrupt: a " + name + " claims " + std::to_string(n) + " elements, limit " +
			std::to_string(kMaxElements) + ")");
}
}  // namespace

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

/** MRPT deserializes a bool by copying the stored byte into it: a corrupt rawlog
 * leaves values other than 0/1 in bool fields, and reading those is undefined
 * behaviour (UBSan in tests/fuzz/fuzz_rawlog). Normalize, through bytes, the
 * flags of the scans the maps read. */
static void normalizeBools(CObservation& o)
{
	auto fix = [](bool& b) {
		unsigned char r;
		std::memcpy(&r, &b, 1);
		r = r != 0;
		std::memcpy(&b, &r, 1);
	};
	if (auto* s3 = dynamic_cast<CObservation3DRangeScan*>(&o))
	{
		fix(s3->hasPoints3D);
		fix(s3->hasRangeImage);
		fix(s3->range_is_depth);
		fix(s3->hasIntensityImage);
		fix(s3->hasConfidenceImage);
	}
	else if (auto* s2 = dynamic_cast<CObservation2DRangeScan*>(&o))
		fix(s2->rightToLeft);
}

void RawlogFrameReader::handleObservation(const CObservation::Ptr& o)
{
	if (!o) return;
	normalizeBools(*o);
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
		PeekStream ps(m_in);
		checkContainerCount(ps, "cannot read rawlog " + m_path + " at entry " + std::to_string(m_entry));
		try
		{
			auto ar = mrpt::serialization::archiveFrom(ps);
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
