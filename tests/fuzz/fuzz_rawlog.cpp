// libFuzzer target: rawlog bytes -> the mapper's streaming reader
// (gam::mapper::RawlogFrameReader, both rawlog formats, plain or gzip) -> every
// frame into CElevation25DMap, CGroundAwareOccupancyGrid, CHeightBandOccupancyGrid
// and COctoMapGrid2D. Exceptions are the expected answer to corrupt data; crashes,
// sanitizer reports, leaks and hangs are bugs. Run: scripts/run-fuzzers.sh.
#include <gam/mapper/RawlogFrames.h>
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <exception>
#include <string>

#include "fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size)
{
	static const std::string path = "/tmp/gam_fuzz_rawlog_" + std::to_string(getpid()) + ".rawlog";
	{
		FILE* f = std::fopen(path.c_str(), "wb");
		if (!f) return 0;
		std::fwrite(data, 1, size, f);
		std::fclose(f);
	}
	auto maps = gamfuzz::freshMaps();
	try
	{
		gam::mapper::RawlogFrameReader rd(path);
		gam::mapper::Frame fr;
		for (int n = 0; n < 8 && rd.next(fr); n++)
			for (auto& m : maps)
			{
				try
				{
					m->insertObservation(*fr.obs, fr.robotPose);
				}
				catch (const std::exception&)
				{
				}
			}
	}
	catch (const std::exception&)
	{
	}
	return 0;
}
