# SPDX-License-Identifier: Apache-2.0
# CPack: the Debian packages of the install tree (owner: daemon engineer), one per component:
#   weedspray        the sprayer: weedsprayd, sprayctl, the units, bus policy, models, config
#   weedspray-maps   weedspray-export-map (GDAL and its ~100 libraries stay off the sprayer;
#                    where GDAL is: not the arm64 build)
#   weedspray-fleet  weedspray-fleet and weedspray-cab with their units (libmosquitto, the page)
#   weedspray-lab    weedspray-lab: experiments, vision evaluation and benchmarks
# The extra packages need the sprayer's users, groups and configuration: they depend on it.
# Debian's synopsis line is CPACK_PACKAGE_DESCRIPTION_SUMMARY for all four (CPack takes no
# component's own); each extended description says what the package holds.
# Build packages from a tree configured with -DCMAKE_INSTALL_PREFIX=/usr: GNUInstallDirs then
# puts the configuration in /etc/weedspray, the unit in /usr/lib/systemd/system, and the
# daemon's built-in default config path follows.
set(CPACK_GENERATOR "DEB")
set(CPACK_PACKAGE_NAME "weedspray")
set(CPACK_DEB_COMPONENT_INSTALL ON)
set(CPACK_DEBIAN_SPRAYER_PACKAGE_NAME "weedspray")
# No GDAL in a build (the arm64 sysroot): no weedspray-export-map, no weedspray-maps.
set(weedspray_extra_packages fleet lab)
if(TARGET weedspray-export-map)
  list(PREPEND weedspray_extra_packages maps)
endif()
set(CPACK_COMPONENTS_ALL sprayer ${weedspray_extra_packages})
foreach(component IN LISTS weedspray_extra_packages)
  string(TOUPPER ${component} upper)
  set(CPACK_DEBIAN_${upper}_PACKAGE_NAME "weedspray-${component}")
  set(CPACK_DEBIAN_${upper}_PACKAGE_DEPENDS "weedspray (= ${PROJECT_VERSION})")
endforeach()
string(CONCAT CPACK_COMPONENT_MAPS_DESCRIPTION
  "weedspray-export-map (sprayctl export-map) turns weedsprayd's as-applied\n"
  "log into GeoJSON, GeoPackage or Shapefile maps of the sprayed stretches and\n"
  "the weed density, through GDAL. Kept apart so the sprayer does not carry GDAL.")
string(CONCAT CPACK_COMPONENT_FLEET_DESCRIPTION
  "weedspray-fleet bridges each board's weedsprayd to an MQTT broker (state,\n"
  "alarms, duties; start, stop and other commands); weedspray-cab serves a page\n"
  "for a phone or tablet in the cab showing every board and steering the machine.")
string(CONCAT CPACK_COMPONENT_LAB_DESCRIPTION
  "weedspray-lab runs the controller's loop steps against a simulated hydraulic\n"
  "line (step, ripple, dose, blockage experiments), evaluates weed models on\n"
  "labelled photos and benchmarks the vision pipeline and I/O.")
set(CPACK_PACKAGE_VENDOR "weedspray")
set(CPACK_PACKAGE_CONTACT "weedspray developers <weedspray-dev@lists.weedspray.org>")
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY "${PROJECT_DESCRIPTION}")
# The extended description (CPack puts the summary above it).
# One string, its lines under 80 columns as Debian policy asks.
string(CONCAT CPACK_PACKAGE_DESCRIPTION
  "weedsprayd is the whole controller of a camera-guided, variable-rate weed\n"
  "sprayer on one board: it finds the plants in each camera frame, opens each\n"
  "nozzle's solenoid valve for the share of time the weed ahead of it needs, and\n"
  "holds the line pressure through a return valve. Flow meter, wheel sensor, tank\n"
  "level, alarms and fail-safes run in the same real-time process, a systemd\n"
  "service watched and steered over D-Bus with sprayctl. weedsprayd --sim runs\n"
  "the same code against a simulated hydraulic line.")
set(CPACK_COMPONENT_SPRAYER_DESCRIPTION "${CPACK_PACKAGE_DESCRIPTION}")
# Debian ships binaries without their symbol tables (lintian: unstripped-binary-or-object).
set(CPACK_STRIP_FILES ON)
set(CPACK_DEBIAN_PACKAGE_SECTION "misc")
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)
# Library dependencies from the binaries (dpkg-shlibdeps), plus the D-Bus daemon.
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS ON)
# procps: /bin/kill, the unit's ExecReload (a minimal Debian has no /bin/kill without it).
set(CPACK_DEBIAN_SPRAYER_PACKAGE_DEPENDS "dbus, systemd, procps")
# [gnss] reads the receiver through gpsd, [fleet] joins an MQTT broker such as mosquitto (both
# optional: off by default).
set(CPACK_DEBIAN_SPRAYER_PACKAGE_SUGGESTS "gpsd, weedspray-fleet, weedspray-maps")
set(CPACK_DEBIAN_FLEET_PACKAGE_SUGGESTS "mosquitto")
# The configuration file is a conffile: upgrades keep the user's edits.
set(CPACK_DEBIAN_SPRAYER_PACKAGE_CONTROL_EXTRA
    "${CMAKE_CURRENT_BINARY_DIR}/conffiles;${PROJECT_SOURCE_DIR}/systemd/debian/postinst")
set(CPACK_DEBIAN_PACKAGE_CONTROL_STRICT_PERMISSION ON)
# The arm64 cross build (the arm64 preset): CPack would take the host's architecture from
# dpkg, and dpkg-shlibdeps must look up the aarch64 binaries' libraries in the sysroot, whose
# DEBIAN/shlibs and DEBIAN/symbols (cmake/toolchains/arm64-sysroot.sh) name their packages.
if(CMAKE_CROSSCOMPILING AND CMAKE_SYSTEM_PROCESSOR STREQUAL "aarch64")
  set(CPACK_DEBIAN_PACKAGE_ARCHITECTURE arm64)
  set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS_PRIVATE_DIRS
      "${CMAKE_SYSROOT}/usr/lib/aarch64-linux-gnu" "${CMAKE_SYSROOT}/lib/aarch64-linux-gnu")
endif()
file(WRITE "${CMAKE_CURRENT_BINARY_DIR}/conffiles"
     "${CMAKE_INSTALL_FULL_SYSCONFDIR}/weedspray/weedspray.toml\n")
# Debian policy's documentation: the machine-readable copyright file (DEP-5) and the changelog,
# whose latest entry must name this version.
set(debian_dir "${PROJECT_SOURCE_DIR}/systemd/debian")
file(STRINGS "${debian_dir}/changelog" changelog_top LIMIT_COUNT 1)
if(NOT changelog_top MATCHES "^weedspray \\(${PROJECT_VERSION}\\) ")
  message(FATAL_ERROR "systemd/debian/changelog starts with '${changelog_top}': "
                      "add an entry for version ${PROJECT_VERSION}")
endif()
install(FILES "${debian_dir}/copyright" DESTINATION ${CMAKE_INSTALL_DOCDIR})
weedspray_install_gzipped(weedspray_package_docs "${debian_dir}/changelog" ${CMAKE_INSTALL_DOCDIR})
foreach(component IN LISTS weedspray_extra_packages)
  set(doc_dir "${CMAKE_INSTALL_DATAROOTDIR}/doc/weedspray-${component}")
  install(FILES "${debian_dir}/copyright" DESTINATION "${doc_dir}" COMPONENT ${component})
  weedspray_install_gzipped(weedspray_package_docs "${debian_dir}/changelog" "${doc_dir}"
                            COMPONENT ${component})
endforeach()
include(CPack)
