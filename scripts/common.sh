# Shared by demo.sh and test.sh: install what is missing, then configure and build.
# Sourced, not run.

AGEX_ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
AGEX_BUILD_DIR="${AGEX_BUILD_DIR:-$AGEX_ROOT/build}"
AGEX_JOBS="${AGEX_JOBS:-$(nproc 2>/dev/null || echo 2)}"

# Debian 12 packages agex builds and tests with (OpenMPI: the distributed batch mode;
# pybind11, NumPy, pytest: the Python module and its tests; clang and its runtimes: the fuzzers).
AGEX_PACKAGES=(
  g++ make cmake pkg-config
  libpcl-dev libeigen3-dev libflann-dev
  libopencv-dev libopencv-contrib-dev
  libboost-program-options-dev libboost-iostreams-dev
  nlohmann-json3-dev
  libopenmpi-dev openmpi-bin
  python3-dev python3-numpy python3-pybind11 python3-pytest
  libgtest-dev
  libdlib-dev
  clang libclang-rt-14-dev
)

agex_install_dependencies () {
  local missing=()
  for pkg in "${AGEX_PACKAGES[@]}"; do
    dpkg-query -W -f='${Status}' "$pkg" 2>/dev/null | grep -q "install ok installed" || missing+=("$pkg")
  done
  if [ ${#missing[@]} -eq 0 ]; then
    echo "agex: all build dependencies are installed"
    return 0
  fi
  echo "agex: installing missing Debian packages: ${missing[*]}"
  local sudo=""
  if [ "$(id -u)" -ne 0 ]; then
    command -v sudo >/dev/null || { echo "agex: need root or sudo to install ${missing[*]}" >&2; return 1; }
    sudo="sudo"
  fi
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"
}

# agex_build [extra cmake args...]
agex_build () {
  echo "agex: configuring in $AGEX_BUILD_DIR"
  cmake -S "$AGEX_ROOT" -B "$AGEX_BUILD_DIR" -DCMAKE_BUILD_TYPE=Release "$@" >/dev/null
  echo "agex: building with $AGEX_JOBS jobs"
  cmake --build "$AGEX_BUILD_DIR" -j "$AGEX_JOBS"
}
