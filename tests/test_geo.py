import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from ftlbo_mav.geo import LocalFrame
from ftlbo_mav.scenario import load_scenario

from .conftest import EXAMPLE

SCENARIO = load_scenario(EXAMPLE)
LAT = sorted([SCENARIO.corner_a.lat_deg, SCENARIO.corner_b.lat_deg])
LON = sorted([SCENARIO.corner_a.lon_deg, SCENARIO.corner_b.lon_deg])


@settings(max_examples=200, deadline=None)
@given(
    lat=st.floats(*LAT),
    lon=st.floats(*LON),
    alt=st.floats(0.0, 120.0),
)
def test_lla_enu_round_trip_within_a_millimetre_in_the_area(lat, lon, alt):
    frame = SCENARIO.frame
    enu = frame.to_enu(lat_deg=lat, lon_deg=lon, alt_m=alt)
    lat2, lon2, alt2 = frame.to_lla(enu)
    back = frame.to_enu(lat_deg=lat2, lon_deg=lon2, alt_m=alt2)
    assert np.linalg.norm(back - enu) < 1e-3
    # 1 mm is about 9e-9 degrees of latitude.
    assert abs(lat2 - lat) < 1e-8 and abs(lon2 - lon) < 1e-8 and abs(alt2 - alt) < 1e-3


def test_origin_is_the_south_west_corner_and_axes_point_east_north_up():
    frame = SCENARIO.frame
    assert np.allclose(frame.to_enu(lat_deg=LAT[0], lon_deg=LON[0]), 0, atol=1e-6)
    east = frame.to_enu(lat_deg=LAT[0], lon_deg=LON[1])
    north = frame.to_enu(lat_deg=LAT[1], lon_deg=LON[0])
    up = frame.to_enu(lat_deg=LAT[0], lon_deg=LON[0], alt_m=10.0)
    assert east[0] > 80 and abs(east[1]) < 0.01
    assert north[1] > 45 and abs(north[0]) < 0.01
    assert np.allclose(up, [0, 0, 10], atol=1e-6)


def test_vectorized_conversion_keeps_shape():
    frame = LocalFrame(origin_lat_deg=-33.9, origin_lon_deg=151.2)
    enu = np.zeros((4, 5, 3))
    lat, lon, alt = frame.to_lla(enu)
    assert lat.shape == (4, 5) and np.allclose(lat, -33.9) and np.allclose(lon, 151.2)


@settings(max_examples=50, deadline=None)
@given(points=st.lists(st.tuples(st.floats(*LAT), st.floats(*LON), st.floats(0.0, 120.0)),
                       min_size=1, max_size=5))
def test_a_few_points_as_floats_convert_as_the_same_points_as_an_array(points):
    """One report's or a few reports' floats take a remembered path (a flight asks for
    the same positions many times); they convert exactly as an array does."""
    frame = SCENARIO.frame
    lat, lon, alt = (list(map(float, c)) for c in zip(*points))
    as_array = frame.to_enu(lat_deg=np.array(lat), lon_deg=np.array(lon), alt_m=np.array(alt))
    for _ in range(2):  # converted, then remembered
        assert np.array_equal(frame.to_enu(lat_deg=lat, lon_deg=lon, alt_m=alt), as_array)
        one = frame.to_enu(lat_deg=lat[0], lon_deg=lon[0], alt_m=alt[0])
        assert one.shape == (3,) and np.array_equal(one, as_array[0])
