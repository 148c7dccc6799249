"""The seas not in slabs under dense packs, shared by the distributed-run
checks (tests/parallel/check_whole_seas.py) and scripts/validate_ranks (its
bem_pack and tank_pack): per case the sea's [sea] table and the `floesim
pack` arguments of its pack, a pack at 70 % cover (seed 3, 0.2 m thick)
whose floes are smaller than a few cells, so that many cells hold pieces
of several floes.
"""


def spectral(dims, width, ny, floes, tank=False):
    """A spectral sea's [sea] 24 m long and `width` m wide on 96 x `ny` cells
    (dims = 1: a flume, every cell spans it), 1 m deep, regular waves (with
    `tank`, a wave maker and an absorber 6 m long each), and its pack's
    `floesim pack` arguments: `floes` floes over the sea."""
    return (f"""
[sea]
model = "spectral"
dims = {dims}
size = [24.0, {width:.1f}]
cells = [96, {ny}]
depth = 1.0
rho = 1000.0

[sea.waves]
kind = "regular"
amplitude = 0.05
wavelength = 6.0
""" + ("""
[sea.tank]
enabled = true
generation_length = 6.0
absorption_length = 6.0
""" if tank else ""), ["--floes", str(floes), "--box", "24", f"{width:g}"])


# name: ([sea], pack arguments).
SEAS = {
    # A BEM basin 12 m x 6 m with walls (24 x 12 cells, 2 m deep), a standing wave, 150 floes.
    "bem": ("""
[sea]
model = "bem"
dims = 2
size = [12.0, 6.0]
cells = [24, 12]
depth = 2.0
rho = 1000.0

[sea.waves]
kind = "standing"
amplitude = 0.05
wavelength = 24.0
""", ["--floes", "150", "--box", "12", "6"]),
    "tank": spectral(2, 6.0, 24, 100, tank=True),
    "flume": spectral(1, 2.0, 1, 40),
    "wide": spectral(1, 8.0, 1, 160),
}


def pack_command(floesim, case, out):
    """The `floesim pack` command that writes `case`'s pack to `out`."""
    return [str(floesim), "pack", *SEAS[case][1], "--concentration", "0.7", "--seed", "3", "--thickness", "0.2",
            "-o", str(out)]
