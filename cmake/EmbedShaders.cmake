# vkray_embed_shaders(TARGET <name> SHADERS <file.comp>...)
# Compiles GLSL compute shaders to SPIR-V with glslangValidator at build time and embeds each as a
# uint32_t array named after the file (raycast.comp -> raycast_comp) in a generated header
# <file>.spv.h, so the binary needs no shader files at run time. glslang writes a depfile, so
# editing any #included file recompiles the shader. <name> is an interface library that carries the
# include path and the build order.
function(vkray_embed_shaders)
  cmake_parse_arguments(ARG "" "TARGET" "SHADERS" ${ARGN})
  set(out_dir ${CMAKE_CURRENT_BINARY_DIR}/generated)
  set(headers)
  foreach(shader IN LISTS ARG_SHADERS)
    string(MAKE_C_IDENTIFIER ${shader} array_name)
    set(source ${CMAKE_CURRENT_SOURCE_DIR}/${shader})
    set(header ${out_dir}/${shader}.spv.h)
    add_custom_command(
      OUTPUT ${header}
      COMMAND ${CMAKE_COMMAND} -E make_directory ${out_dir}
      COMMAND ${GLSLANG_VALIDATOR} --quiet --target-env vulkan1.1 --vn ${array_name}
              --depfile ${header}.d -o ${header} ${source}
      DEPENDS ${source}
      DEPFILE ${header}.d
      COMMENT "Compiling ${shader} to SPIR-V"
      VERBATIM)
    list(APPEND headers ${header})
  endforeach()
  add_custom_target(${ARG_TARGET}_spirv DEPENDS ${headers})
  add_library(${ARG_TARGET} INTERFACE)
  target_include_directories(${ARG_TARGET} INTERFACE ${out_dir})
  add_dependencies(${ARG_TARGET} ${ARG_TARGET}_spirv)
endfunction()
