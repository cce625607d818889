"""Side by side with the published peer code: pyTerramechanics' WongReece.py.

Reference numbers: jcmadsen/pyTerramechanics, commit 11ef69df6b57848baafa582852a8204199d870c9
(2014-01-04), `WongReece.py` with the parameters of `plot_WongReece.py` (Wong & Reece 1967
Part II sand cases, converted from inch-pound to SI), run with SciPy outside this
repository; driven wheel, theta_r = 0.  The code uses Reece's law with k1 = c k'_c [Pa] and
k2 = gamma k'_phi [N/m^3] lumped, so here k'_c = k1 / c and gamma = 1 N/m^3, k'_phi = k2.
An independent SciPy recomputation agreed with the peer code to 3e-11, so its numbers are
converged.  Columns: slip, sinkage z0 [m], drawbar pull [N], torque [N m].
"""

import numpy as np
import pytest

import snowjax as sj

PEER = {
    "compact_sand": (
        dict(
            n=0.47,
            k1=137895.14586336722,
            k2=678617.8438157835,
            c=689.4757293168361,
            phi=0.5811946409141117,
            K=0.038099999999999995,
            r=0.6273799999999999,
            b=0.15239999999999998,
            W=8923.132560212562,
            c1=0.43,
            c2=0.32,
        ),
        [
            (0.05, 0.12304333104769291, 245.07884267611442, 1888.6379079650562),
            (0.1, 0.12270691193516128, 673.7604069084979, 2154.1608025464957),
            (0.2, 0.12309508064132, 1215.419442321981, 2501.63905167414),
            (0.3, 0.12451411716489984, 1507.0696034721725, 2705.418307037882),
            (0.4, 0.12672716587813854, 1659.4638737775558, 2831.054510208449),
            (0.5, 0.12963986155792137, 1728.7822721381942, 2911.9652450484105),
            (0.6, 0.13324365957613693, 1744.612072916904, 2966.0285184342874),
        ],
    ),
    "loose_sand": (
        dict(
            n=1.15,
            k1=0.0,
            k2=542894.2750526269,
            c=827.3708751802033,
            phi=0.5427973973702365,
            K=0.038099999999999995,
            r=0.6273799999999999,
            b=0.15239999999999998,
            W=8834.168127907353,
            c1=0.18,
            c2=0.32,
        ),
        [
            (0.05, 0.27085836910533495, 990.8569321078953, 2749.630718961651),
            (0.1, 0.2723641512534264, 1045.549789605428, 2808.9717958091055),
            (0.2, 0.2762512574547431, 1058.0338797756515, 2875.0576308843156),
            (0.3, 0.28107069092914244, 1002.2014057623461, 2906.60449726654),
            (0.4, 0.2867081033970576, 910.8204071771332, 2922.8827261482456),
            (0.5, 0.2931527758669102, 797.0913963290759, 2931.941474343912),
            (0.6, 0.30045365030749577, 666.4226998525936, 2937.4921163780205),
        ],
    ),
    "loose_sand_wide": (
        dict(
            n=1.15,
            k1=0.0,
            k2=542894.2750526269,
            c=827.3708751802033,
            phi=0.5427973973702365,
            K=0.038099999999999995,
            r=0.6273799999999999,
            b=0.30479999999999996,
            W=9274.542067818142,
            c1=0.18,
            c2=0.32,
        ),
        [
            (0.05, 0.19833384890841596, 1115.3664649298332, 2599.625624226198),
            (0.1, 0.1989650223780122, 1321.2701192079876, 2745.2528342322867),
            (0.2, 0.2011154100110535, 1522.0099460158776, 2914.367776648318),
            (0.3, 0.2041392392361167, 1572.8576049165515, 2998.9643984142217),
            (0.4, 0.20785477550431788, 1549.2307921196052, 3043.9282003228054),
            (0.5, 0.21219734998350878, 1484.12663794077, 3069.020250818527),
            (0.6, 0.2171661364456153, 1392.6732280087542, 3083.534010315608),
        ],
    ),
}


@pytest.mark.parametrize("case", sorted(PEER))
def test_wong_reece_matches_pyterramechanics(case):
    p, rows = PEER[case]
    soil = sj.ReeceSoil(
        p["n"], p["k1"] / p["c"], p["k2"], 1.0, p["c"], np.tan(p["phi"]), shear_modulus=p["K"]
    )
    slips = np.array([r[0] for r in rows])
    st = sj.solve_wheel(
        sj.RigidWheel(2 * p["r"], p["b"]),
        sj.ContactModel(soil, sj.WongReece(p["c1"], p["c2"])),
        p["W"],
        slips,
    )
    assert np.all(np.asarray(st.status) == sj.Status.CONVERGED)
    ref = np.array([r[1:] for r in rows])
    got = np.stack([st.sinkage, st.drawbar_pull, st.torque], 1)
    np.testing.assert_allclose(got, ref, rtol=1e-7)
