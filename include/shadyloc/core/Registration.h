/* ShadyLoc — registration of our classes with MRPT's RTTI system. */
#pragma once

namespace shadyloc
{
/** Registers every RTTI/serialisable class of ShadyLoc (idempotent). The
 * classes also register themselves when libshadyloc loads (each in the file
 * that defines it); the plugin and apps call this explicitly too. */
void registerAllClasses();
}  // namespace shadyloc
