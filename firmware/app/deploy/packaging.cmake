# Installation layout and the Debian package of the controller (docs/deploy.md).
# Included at the end of the top CMakeLists.txt, after every target exists.
#
#   cmake --install build --prefix X   X/bin/landscaped, X/etc/landscape/landscaped.conf,
#                                      X/etc/landscape/gateway.toml (mode 0640: password hashes),
#                                      X/lib/systemd/system/landscaped.service,
#                                      X/lib/systemd/system/landscape-gateway.service,
#                                      X/lib/sysusers.d/landscape.conf,
#                                      X/lib/udev/rules.d/60-landscape-gpio.rules,
#                                      X/lib/udev/rules.d/60-landscape-input.rules,
#                                      X/share/doc/landscape/*.md,
#                                      X/share/landscape/robots/*.ini (the robot model files)
#   cd build && cpack -G DEB           landscape-controller_<version>_<arch>.deb
#
# With the prefix /usr (the package, or a system install) the configuration
# goes to /etc, as GNUInstallDirs does it: /usr/etc is read by nobody.
set(LS_DEPLOY_DIR ${CMAKE_CURRENT_LIST_DIR})
set(LS_DEB_MAINTAINER "LandScape-over-CAN maintainers <landscape@localhost>"
    CACHE STRING "Maintainer field of the Debian package: who answers for this build")

if(NOT TARGET landscaped)
  message(FATAL_ERROR "packaging.cmake: include it after the landscaped target is defined")
endif()

install(TARGETS landscaped RUNTIME DESTINATION bin)
# The simulated drives, and their EDS, which the shipped configuration names
# until the user's drives replace it (docs/deploy.md "Drives").
if(TARGET ls-simdrives)
  install(TARGETS ls-simdrives RUNTIME DESTINATION bin)
endif()
install(FILES ${PROJECT_SOURCE_DIR}/hal/sim/drives/ls-simdrive.eds DESTINATION share/landscape)

install(CODE "
  if(CMAKE_INSTALL_PREFIX STREQUAL \"/usr\")
    set(_ls_etc \"/etc/landscape\")
  else()
    set(_ls_etc \"\${CMAKE_INSTALL_PREFIX}/etc/landscape\")
  endif()
  file(INSTALL DESTINATION \"\${_ls_etc}\" TYPE FILE PERMISSIONS OWNER_READ OWNER_WRITE GROUP_READ WORLD_READ
       FILES \"${LS_DEPLOY_DIR}/landscaped.conf\")
  file(INSTALL DESTINATION \"\${_ls_etc}\" TYPE FILE PERMISSIONS OWNER_READ OWNER_WRITE GROUP_READ
       FILES \"${LS_DEPLOY_DIR}/gateway.toml\")
")

install(FILES ${LS_DEPLOY_DIR}/landscaped.service ${LS_DEPLOY_DIR}/landscape-gateway.service
        DESTINATION lib/systemd/system)
install(FILES ${LS_DEPLOY_DIR}/landscape.sysusers DESTINATION lib/sysusers.d RENAME landscape.conf)
install(FILES ${LS_DEPLOY_DIR}/60-landscape-gpio.rules ${LS_DEPLOY_DIR}/60-landscape-input.rules
        DESTINATION lib/udev/rules.d)
# The shipped robot model files ([robot] model = /usr/share/landscape/robots/ur5e.ini).
file(GLOB LS_ROBOT_FILES CONFIGURE_DEPENDS ${PROJECT_SOURCE_DIR}/firmware/model/robots/*.ini)
install(FILES ${LS_ROBOT_FILES} DESTINATION share/landscape/robots)
file(GLOB LS_DOC_FILES CONFIGURE_DEPENDS ${PROJECT_SOURCE_DIR}/docs/*.md)
install(FILES ${LS_DOC_FILES} DESTINATION share/doc/landscape)

# ---- CPack: one Debian package ------------------------------------------------
set(CPACK_GENERATOR DEB)
set(CPACK_PACKAGE_NAME landscape-controller)
set(CPACK_PACKAGE_VERSION ${PROJECT_VERSION})
set(CPACK_PACKAGE_VENDOR "LandScape-over-CAN")
set(CPACK_PACKAGE_CONTACT "${LS_DEB_MAINTAINER}")
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY "LandScape robot controller daemon (landscaped) over CAN")
string(CONCAT CPACK_PACKAGE_DESCRIPTION
    "landscaped runs the LandScape command set over CAN (SocketCAN or SLCAN) with a fixed-rate\n"
    "control loop, CiA 402 servo drives on a CANopen bus of their own, digital I/O through libgpiod\n"
    "and a simulated 6-DOF arm (also behind simulated drives: ls-simdrives). Includes the systemd\n"
    "unit, the landscape user and udev rules for /dev/gpiochip* and /dev/input/event* (teach\n"
    "pendants and 6-DOF mice through evdev), and the unit and configuration of\n"
    "the OPC UA gateway (landscape gateway, from the host tool).")
# The package installs under /usr; DESTDIR staging lets the configuration
# rule above place /etc/landscape (an absolute path) into the package.
set(CPACK_PACKAGING_INSTALL_PREFIX /usr)
set(CPACK_INSTALL_PREFIX /usr)
set(CPACK_SET_DESTDIR ON)
set(CPACK_STRIP_FILES ON)
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)
set(CPACK_DEBIAN_PACKAGE_MAINTAINER "${LS_DEB_MAINTAINER}")
set(CPACK_DEBIAN_PACKAGE_SECTION misc)
set(CPACK_DEBIAN_PACKAGE_PRIORITY optional)
# Named explicitly (the controller loads them, whatever the linker kept) and
# completed by dpkg-shlibdeps (libc6, libstdc++6, ...).
set(CPACK_DEBIAN_PACKAGE_DEPENDS "libode8, libgpiod2, libinih1, libevdev2")
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS ON)
set(CPACK_DEBIAN_PACKAGE_RECOMMENDS "can-utils, gpiod")
set(CPACK_DEBIAN_PACKAGE_CONTROL_EXTRA
    ${LS_DEPLOY_DIR}/conffiles ${LS_DEPLOY_DIR}/postinst ${LS_DEPLOY_DIR}/prerm ${LS_DEPLOY_DIR}/postrm)
set(CPACK_DEBIAN_PACKAGE_CONTROL_STRICT_PERMISSION ON)
include(CPack)
