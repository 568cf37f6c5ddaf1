/* A stand-alone MRPT program that knows nothing of ShadyLoc: it loads a
 * plugin module (as `rawlog-edit -p` does), then reads a serialised metric
 * map from a file through MRPT's class registry and prints its class and
 * summary. Used by the map tests to show a map file opens in another process
 * with only the plugin.
 *   kfmap_load PLUGIN.so MAPFILE  -> exit 0 and "class: ..." on success */
#include <mrpt/io/CFileGZInputStream.h>
#include <mrpt/maps/CMetricMap.h>
#include <mrpt/serialization/CArchive.h>
#include <mrpt/system/os.h>

#include <iostream>

int main(int argc, char** argv)
{
	if (argc != 3)
	{
		std::cerr << "usage: kfmap_load PLUGIN.so MAPFILE\n";
		return 2;
	}
	try
	{
		std::string err;
		if (!mrpt::system::loadPluginModule(argv[1], err))
		{
			std::cerr << "cannot load plugin '" << argv[1] << "': " << err << "\n";
			return 1;
		}
		mrpt::io::CFileGZInputStream f(argv[2]);
		auto obj = mrpt::serialization::archiveFrom(f).ReadObject();
		auto map = std::dynamic_pointer_cast<mrpt::maps::CMetricMap>(obj);
		if (!map)
		{
			std::cerr << argv[2] << ": not a metric map\n";
			return 1;
		}
		std::cout << "class: " << map->GetRuntimeClass()->className << "\n" << map->asString() << "\n";
		return 0;
	}
	catch (const std::exception& e)
	{
		std::cerr << "error: " << e.what() << "\n";
		return 1;
	}
}
