# SPDX-License-Identifier: Apache-2.0
# weedspray_install_gzipped(TARGET SOURCE DESTINATION [RENAME NAME] [COMPONENT NAME])
#   Installs SOURCE compressed as Debian policy wants man pages and changelogs: gzip -9 without
#   the name and time stamp (-n), so a rebuild makes the same bytes. TARGET (a custom target
#   made when missing) builds the .gz files with ALL.
function(weedspray_install_gzipped target source destination)
  cmake_parse_arguments(ARG "" "RENAME;COMPONENT" "" ${ARGN})
  get_filename_component(name "${source}" NAME)
  if(ARG_RENAME)
    set(name "${ARG_RENAME}")
  endif()
  if(NOT ARG_COMPONENT)
    set(ARG_COMPONENT "${CMAKE_INSTALL_DEFAULT_COMPONENT_NAME}")
  endif()
  set(gz "${CMAKE_CURRENT_BINARY_DIR}/gz/${ARG_COMPONENT}/${name}.gz")
  add_custom_command(OUTPUT "${gz}"
    COMMAND ${CMAKE_COMMAND} -E make_directory "${CMAKE_CURRENT_BINARY_DIR}/gz/${ARG_COMPONENT}"
    COMMAND sh -c "gzip -9nc \"$1\" >\"$2\"" sh "${source}" "${gz}"
    DEPENDS "${source}"
    VERBATIM)
  if(NOT TARGET ${target})
    add_custom_target(${target} ALL)
  endif()
  target_sources(${target} PRIVATE "${gz}")
  install(FILES "${gz}" DESTINATION "${destination}" COMPONENT "${ARG_COMPONENT}")
endfunction()
