#include <gam/mapper/Errors.h>
#include <gam/mapper/RawlogFrames.h>
#include <mrpt/img/CImage.h>
#include <mrpt/obs/CActionCollection.h>
#include <mrpt/obs/CObservation2DRangeScan.h>
#include <mrpt/obs/CObservation3DRangeScan.h>
#include <mrpt/obs/CObservationOdometry.h>
#include <mrpt/obs/CRawlog.h>
#include <mrpt/obs/CSensoryFrame.h>
#include <mrpt/poses/CPosePDF.h>
#include <mrpt/serialization/CArchive.h>
#include <mrpt/system/filesystem.h>

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <new>
#include <optional>
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
/** A read-only view of the rawlog stream that can look ahead into the next object
 * before MRPT deserializes it (the checks below: counts MRPT 2.5 allocates before
 * reading, pointers it does not check; found by tests/fuzz/fuzz_rawlog). In a
 * well-formed rawlog the bytes peeked never go past the object being read, so the
 * buffer is always consumed by the reads that follow; in a corrupt one what is left
 * is lost with the reader's error. */
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

/** The header MRPT writes before every object, read without consuming it. New format
 * (MRPT >= 0.5.5): byte 0x80|L, L name bytes, version byte (none for "nullptr"),
 * and an end byte 0x88 after the object. Old format: uint32 L < 0x80, L name bytes,
 * int32 version, no end byte. */
struct ObjectHeader
{
	std::string name;
	/** The class MRPT reads for `name`: it also finds a class by its name
	 * without the namespace, so "mrpt::/bs::CActionCollection" is one too
	 * (found by tests/fuzz/fuzz_rawlog). nullptr: none (MRPT reports it). */
	const mrpt::rtti::TRuntimeClassId* cls = nullptr;
	int version = -1;
	size_t bytes = 0;  ///< header length
	bool oldFormat = false;

	template <class T>
	bool is() const
	{
		return cls == CLASS_ID(T);
	}
};

/** The header of the object starting `at` bytes ahead; nullopt when it is cut short
 * or malformed (MRPT's own reader then reports it). */
std::optional<ObjectHeader> peekHeader(PeekStream& ps, size_t at)
{
	if (ps.peek(at + 1) < at + 1) return std::nullopt;
	ObjectHeader h;
	size_t L = ps.data()[at] & 0x7F, p = at + 1;
	h.oldFormat = !(ps.data()[at] & 0x80);
	if (h.oldFormat)
	{
		if (ps.peek(at + 4) < at + 4 || ps.data()[at + 1] || ps.data()[at + 2] || ps.data()[at + 3])
			return std::nullopt;
		p = at + 4;
	}
	if (ps.peek(p + L) < p + L) return std::nullopt;
	// As MRPT reads it: a C string, so a NUL byte ends the name.
	h.name = std::string(reinterpret_cast<const char*>(ps.data()) + p, L).c_str();
	if (h.name != "nullptr") h.cls = mrpt::rtti::findRegisteredClass(h.name);
	p += L;
	if (!h.oldFormat && h.name == "nullptr")
	{
		h.bytes = p - at;
		return h;
	}
	const size_t vbytes = h.oldFormat ? 4 : 1;
	if (ps.peek(p + vbytes) < p + vbytes) return std::nullopt;
	h.version = ps.data()[p];  // the old format's int32 is < 255 (MRPT asserts)
	h.bytes = p + vbytes - at;
	return h;
}

uint32_t le32(const uint8_t* c)
{
	return uint32_t(c[0]) | uint32_t(c[1]) << 8 | uint32_t(c[2]) << 16 | uint32_t(c[3]) << 24;
}

uint32_t peekU32(PeekStream& ps, size_t at) { return ps.peek(at + 4) < at + 4 ? 0 : le32(ps.data() + at); }

/** Thrown with the whole message: the reader passes it on unchanged. */
struct CorruptRawlog : std::runtime_error
{
	using std::runtime_error::runtime_error;
};

/** Where a container's uint32 element count lies after its header:
 * CActionCollection version 0, CSensoryFrame version 2 right after it; a
 * CSensoryFrame of version 1 after a uint32 ID, of version 0 also after a
 * timestamp. npos: not such a container. */
size_t countOffset(const ObjectHeader& h)
{
	if (h.is<mrpt::obs::CActionCollection>()) return h.version == 0 ? 0 : std::string::npos;
	if (h.is<mrpt::obs::CSensoryFrame>())
		return h.version == 2 ? 0 : h.version == 1 ? 4 : h.version == 0 ? 12 : std::string::npos;
	return std::string::npos;
}

/** Rejects a CSensoryFrame / CActionCollection (header h, at the stream's start)
 * whose element count is absurd. */
void checkContainerCount(PeekStream& ps, const ObjectHeader& h, const std::string& where)
{
	const size_t off = countOffset(h);
	if (off == std::string::npos) return;
	const size_t at = h.bytes + off;
	if (ps.peek(at + 4) < at + 4) return;
	const uint32_t n = peekU32(ps, at);
	constexpr uint32_t kMaxElements = 100000;
	if (n > kMaxElements)
		throw CorruptRawlog(
			where + " (corrupt: a " + h.name + " claims " + std::to_string(n) + " elements, limit " +
			std::to_string(kMaxElements) + ")");
}

/** MRPT 2.5's CObservation3DRangeScan allocates its five point buffers (x, y, z
 * floats, two uint16 pixel indices: 16 bytes a point) for the stored count before
 * reading a point: a corrupt count makes it ask for up to 1 GiB a buffer
 * (mrpt::aligned_malloc's limit above), 4 GiB in all, before the read fails
 * (found by tests/fuzz/fuzz_rawlog; the fuzzer's memory limit, a walker's
 * computer's RAM). Layout: float maxRange, the sensor pose (a CPose3D object:
 * version 3 is 12 doubles), bool hasPoints3D (not in version 0), uint32 count. */
void checkRangeScan3D(PeekStream& ps, const ObjectHeader& h, const std::string& where)
{
	if (!h.is<mrpt::obs::CObservation3DRangeScan>()) return;
	size_t p = h.bytes + 4;
	const auto pose = peekHeader(ps, p);
	if (!pose || !pose->is<mrpt::poses::CPose3D>() || pose->version != 3) return;
	p += pose->bytes + 12 * 8 + (pose->oldFormat ? 0 : 1);
	if (h.version >= 1)  // version 0 has points always, and no flag
	{
		if (ps.peek(p + 1) < p + 1 || ps.data()[p] == 0) return;
		p += 1;
	}
	if (ps.peek(p + 4) < p + 4) return;
	const uint32_t points = peekU32(ps, p);
	// 2^25 points, 512 MiB: four times a 4096 x 2048 depth image.
	constexpr uint32_t kMaxPoints = 1u << 25;
	if (points > kMaxPoints)
		throw CorruptRawlog(
			where + " (corrupt: a CObservation3DRangeScan claims " + std::to_string(points) + " points, limit " +
			std::to_string(kMaxPoints) + ")");
}

/** Two checks of a CActionRobotMovement2D before MRPT 2.5 reads it (both found by
 * tests/fuzz/fuzz_rawlog):
 * - its pose PDF is read as a typed pointer: a stored object of another class (or
 *   "nullptr") gives a null pointer, which MRPT then copies with clone(), a SIGSEGV
 *   (here an estimation method other than odometry, so the odometry's CPose2D was
 *   read as the PDF);
 * - with odometry and Thrun's motion model, the stored particle count is allocated
 *   as is: a corrupt one asks for gigabytes.
 * Layout: versions 0-1 store the PDF first; versions >= 2 an int32 method, then the
 * PDF unless the method is odometry (0); odometry (versions 3-7): the increment (a
 * CPose2D object), int32 model (0 = Gaussian), 5 (version 3) or 6 floats, uint32
 * particle count. */
void checkRobotMovement2D(PeekStream& ps, const ObjectHeader& h, const std::string& where)
{
	if (!h.is<mrpt::obs::CActionRobotMovement2D>()) return;
	size_t p = h.bytes;
	const bool odometry = h.version >= 2 && ps.peek(p + 4) >= p + 4 && peekU32(ps, p) == 0;
	if (h.version >= 2) p += 4;
	if (odometry)
	{
		const auto inc = peekHeader(ps, p);
		if (h.version < 3 || h.version > 7 || !inc || !inc->is<mrpt::poses::CPose2D>() || inc->version > 1)
			return;  // MRPT reports what it cannot read
		p += inc->bytes + (inc->version == 0 ? 12 : 24) + (inc->oldFormat ? 0 : 1);
		const uint32_t model = peekU32(ps, p);
		p += 4 + (h.version == 3 ? 5 : 6) * 4;
		if (ps.peek(p + 4) < p + 4) return;
		const uint32_t particles = peekU32(ps, p);
		constexpr uint32_t kMaxParticles = 100000;  // MRPT's default is 300
		if (model != 0 && particles > kMaxParticles)
			throw CorruptRawlog(
				where + " (corrupt: a CActionRobotMovement2D asks for " + std::to_string(particles) +
				" motion-model particles, limit " + std::to_string(kMaxParticles) + ")");
		return;
	}
	const auto pdf = peekHeader(ps, p);
	if (!pdf) return;
	if (!pdf->cls || !pdf->cls->derivedFrom(CLASS_ID(mrpt::poses::CPosePDF)))
		throw CorruptRawlog(
			where + " (corrupt: a CActionRobotMovement2D holds a '" + pdf->name + "' where its pose PDF should be)");
}

/** The checks of the object at the stream's start (header h) that MRPT would
 * otherwise read in one go, alone or with its container. */
void checkObject(PeekStream& ps, const ObjectHeader& h, const std::string& where)
{
	checkContainerCount(ps, h, where);
	checkRobotMovement2D(ps, h, where);
	checkRangeScan3D(ps, h, where);
}

void add(mrpt::obs::CActionCollection& c, const mrpt::obs::CAction::Ptr& a) { c.insertPtr(a); }
void add(mrpt::obs::CSensoryFrame& c, const mrpt::obs::CObservation::Ptr& o) { c.insert(o); }

/** Reads a CActionCollection (version 0) or a CSensoryFrame (version 2) element by
 * element, so that each element is checked before MRPT reads it (MRPT's own reader
 * reads them all in one call). Their wire format: header, uint32 count, the
 * elements, end byte. Null elements are left out; an element of another base class
 * is an error. */
template <class Element, class Container>
void readElements(
	PeekStream& ps, mrpt::serialization::CArchive& ar, const ObjectHeader& h, const std::string& where, Container& into)
{
	std::vector<uint8_t> head(h.bytes + 4);
	if (ps.Read(head.data(), head.size()) != head.size())
		throw CorruptRawlog(where + " (corrupt: the file ends inside a " + h.name + ")");
	const uint32_t n = le32(head.data() + h.bytes);
	for (uint32_t i = 0; i < n; i++)
	{
		// An element of another class would be read in full by MRPT, unchecked
		// (a collection inside a collection: its count allocated as is; found by
		// tests/fuzz/fuzz_rawlog), then dropped: it is corrupt data.
		if (const auto e = peekHeader(ps, 0))
		{
			if (e->cls && !e->cls->derivedFrom(CLASS_ID(Element)))
				throw CorruptRawlog(where + " (corrupt: a " + h.name + " holds a '" + e->name + "')");
			checkObject(ps, *e, where);
		}
		if (auto e = ar.ReadObject<Element>()) add(into, e);
	}
	if (!h.oldFormat)
	{
		uint8_t end = 0;
		if (ps.Read(&end, 1) != 1 || end != 0x88)
			throw CorruptRawlog(where + " (corrupt: a " + h.name + " without its end byte)");
	}
}

/** The next top-level object, with the checks above before MRPT reads it. */
mrpt::serialization::CSerializable::Ptr readObject(PeekStream& ps, const std::string& where)
{
	auto ar = mrpt::serialization::archiveFrom(ps);
	const auto h = peekHeader(ps, 0);
	if (h) checkObject(ps, *h, where);
	if (h && h->is<mrpt::obs::CActionCollection>() && h->version == 0)
	{
		auto acts = mrpt::obs::CActionCollection::Create();
		readElements<mrpt::obs::CAction>(ps, ar, *h, where, *acts);
		return acts;
	}
	if (h && h->is<mrpt::obs::CSensoryFrame>() && h->version == 2)
	{
		auto sf = mrpt::obs::CSensoryFrame::Create();
		readElements<mrpt::obs::CObservation>(ps, ar, *h, where, *sf);
		return sf;
	}
	return ar.ReadObject();
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
		try
		{
			obj = readObject(ps, "cannot read rawlog " + m_path + " at entry " + std::to_string(m_entry));
		}
		catch (const CorruptRawlog&)
		{
			throw;
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
