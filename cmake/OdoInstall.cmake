# What `cmake --install` puts where, and the Debian package CPack makes of it (`make package`).
# Rules name targets, not source paths, so moving a file between folders does not touch them.
#
#   PREFIX/bin/                      the CLIs a user runs
#   PREFIX/lib/libodosim.so          the simulator's C API for tools (the Python tools load it)
#   PREFIX/include/odosim/odosim.h   its header
#   PREFIX/share/odometry/           laid out as in the repository, so the CLIs' and the Python
#                                    tools' data lookup is one rule (tools/lib/data_dir.h):
#     can/odometry.dbc               the single source of truth for every frame
#     host_sim/robots/*.json         example robot descriptions (and OptiOdom's, from gap/robots)
#     host_sim/scenarios/*.json      example simulator scenarios
#     hal/cortexm/openocd/*.cfg      odo-flash's openocd configuration
#   PREFIX/share/doc/odometry/       the READMEs
#   PREFIX/share/man/man1/           a man page per CLI, made from its --help (help2man)
#
# The package is meant to hold the release build (`make package`: preset release, -O2, no
# sanitizers); installing from the sanitized host build works but its tools need ASan at run time.
include(GNUInstallDirs)

set(ODO_INSTALL_CLIS odo-sim odo-calib odo-replay odo-params odo-ipec odo-canvec odo-soak odo-bench
    odo-demo)
set(ODO_SHARE "${CMAKE_INSTALL_DATADIR}/odometry")

install(TARGETS ${ODO_INSTALL_CLIS} RUNTIME DESTINATION "${CMAKE_INSTALL_BINDIR}")
# Plain lib/, not the multiarch one: the Python tools look for PREFIX/lib/libodosim.so.
install(TARGETS odosim_shared LIBRARY DESTINATION lib)
install(FILES host_sim/include/odosim/odosim.h DESTINATION "${CMAKE_INSTALL_INCLUDEDIR}/odosim")
install(FILES can/odometry.dbc DESTINATION "${ODO_SHARE}/can")
file(GLOB _odo_robots CONFIGURE_DEPENDS "${CMAKE_SOURCE_DIR}/host_sim/robots/*.json"
     "${CMAKE_SOURCE_DIR}/tools/python/odo_tools/gap/robots/*.json")
install(FILES ${_odo_robots} DESTINATION "${ODO_SHARE}/host_sim/robots")
install(DIRECTORY host_sim/scenarios/ DESTINATION "${ODO_SHARE}/host_sim/scenarios"
        FILES_MATCHING PATTERN "*.json")
install(DIRECTORY hal/cortexm/openocd/ DESTINATION "${ODO_SHARE}/hal/cortexm/openocd"
        FILES_MATCHING PATTERN "*.cfg")

# READMEs under their folder's name: README.md, can.md, host_sim.md, ...
install(FILES README.md DESTINATION "${CMAKE_INSTALL_DOCDIR}")
foreach(dir can host_sim tools tools/calib tools/ipec tools/replay tools/soak firmware hal)
  if(EXISTS "${CMAKE_SOURCE_DIR}/${dir}/README.md")
    string(REPLACE "/" "-" _name "${dir}")
    install(FILES "${dir}/README.md" DESTINATION "${CMAKE_INSTALL_DOCDIR}" RENAME "${_name}.md")
  endif()
endforeach()

# Everything the rules below install, so a build for packaging needs only this target
# (tests/package builds it alone; `cmake --install` copies, it does not build).
add_custom_target(odo_installable)
add_dependencies(odo_installable ${ODO_INSTALL_CLIS} odosim_shared)

# Man pages from each CLI's --help, so they cannot drift from it; NAME lines from this table.
set(_odo_name_odo-sim "simulate the papers' experiments with the firmware in the loop")
set(_odo_name_odo-calib "UMBmark calibration and parameter blocks in firmware images")
set(_odo_name_odo-replay "replay CAN logs or a live bus through the firmware")
set(_odo_name_odo-params "write, show and check parameter blocks")
set(_odo_name_odo-ipec "IPEC figures, traces and self-calibration")
set(_odo_name_odo-canvec "the firmware's CAN codec on stdin and stdout")
set(_odo_name_odo-soak "frame loss at speed and the 24 h fault soak")
set(_odo_name_odo-bench "the firmware's accuracy and speed figures")
set(_odo_name_odo-demo "drive a UMBmark square through the firmware step")
find_program(ODO_HELP2MAN help2man)
if(ODO_HELP2MAN)
  set(_odo_mans "")
  foreach(cli IN LISTS ODO_INSTALL_CLIS)
    if(NOT DEFINED _odo_name_${cli})
      message(FATAL_ERROR "cmake/OdoInstall.cmake: no man page NAME line for ${cli}")
    endif()
    set(_man "${CMAKE_BINARY_DIR}/man/${cli}.1")
    add_custom_command(OUTPUT "${_man}"
      COMMAND "${CMAKE_COMMAND}" -E make_directory "${CMAKE_BINARY_DIR}/man"
      COMMAND "${ODO_HELP2MAN}" --no-info --no-discard-stderr
              "--version-string=${PROJECT_VERSION}" "--name=${_odo_name_${cli}}"
              --output "${_man}" "$<TARGET_FILE:${cli}>"
      DEPENDS ${cli}
      COMMENT "man page ${cli}.1"
      VERBATIM)
    list(APPEND _odo_mans "${_man}")
  endforeach()
  add_custom_target(odo_man ALL DEPENDS ${_odo_mans})
  add_dependencies(odo_installable odo_man)
  install(FILES ${_odo_mans} DESTINATION "${CMAKE_INSTALL_MANDIR}/man1")
else()
  message(STATUS "help2man not found: no man pages (tools/deps.sh installs it)")
endif()

# CPack: one Debian package of everything above, installed under /usr.
set(CPACK_GENERATOR "DEB")
set(CPACK_PACKAGE_NAME "odometry-tools")
set(CPACK_PACKAGE_VENDOR "odometry firmware project")
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY
    "Odometry firmware host tools: simulator, UMBmark calibration, CAN log replay")
set(CPACK_PACKAGE_CONTACT "odometry firmware maintainers <odometry@localhost>")
set(CPACK_PACKAGING_INSTALL_PREFIX "/usr")
set(CPACK_DEBIAN_FILE_NAME "DEB-DEFAULT")
set(CPACK_DEBIAN_PACKAGE_SECTION "electronics")
# Runtime libraries (jansson, GSL, libc) read from the binaries by dpkg-shlibdeps.
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS ON)
set(CPACK_DEBIAN_PACKAGE_SUGGESTS "python3, can-utils")
set(CPACK_STRIP_FILES ON)
include(CPack)
