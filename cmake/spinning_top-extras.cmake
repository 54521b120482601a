# Included by spinning_topConfig.cmake, devel and install space alike, so in every package that
# finds spinning_top (find_package(catkin REQUIRED COMPONENTS spinning_top ...)).
#
# spinning_top's headers need C++17 (std::optional, std::variant). GCC 9, Ubuntu 20.04's (Noetic),
# compiles C++14 by default, and a package that includes them without asking for C++17 fails
# ("'optional' in namespace 'std' does not name a template type"). catkin exports variables, not
# targets with usage requirements, so the requirement travels this way: the finding package's
# C++ standard is raised to 17 unless it already asks for 17 or newer.
if(NOT DEFINED CMAKE_CXX_STANDARD OR CMAKE_CXX_STANDARD EQUAL 98 OR CMAKE_CXX_STANDARD LESS 17)
  if(DEFINED CMAKE_CXX_STANDARD)
    message(STATUS "spinning_top: its headers need C++17: CMAKE_CXX_STANDARD ${CMAKE_CXX_STANDARD} raised to 17")
  endif()
  set(CMAKE_CXX_STANDARD 17)
  set(CMAKE_CXX_STANDARD_REQUIRED ON)
endif()
