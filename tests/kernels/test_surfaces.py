"""The slope memo of a curved surface's block (``S_SLOPE_AT``, ``S_SLOPE``): an offset
inversion that starts where the last one ended takes f'(s) from it instead of calling the
wall function again, with the same bits as the call; never at s = 0 (+0 and -0 compare
equal), and a block handed out by ``Surface.block`` carries none. Run on the twin, with a
wall function that counts its calls."""

from __future__ import annotations

import math

from billiard.kernels.interpreted import layout as L
from billiard.kernels.interpreted import surfaces as K

R = 1.55e-3  # m
A = 8.0  # 1/m, y = A x^2 / 2 + x^3


def f(x, p):
    return 0.5 * A * x * x + x * x * x


def d2f(x, p):
    return A + 6.0 * x


def block(ws):
    ctx = [0.0] * (L.SURF + L.SURF_STRIDE)
    base = L.SURF
    ctx[base + L.S_KIND] = L.CURVED
    ctx[base + L.S_A] = R
    ctx[base + L.S_SLOPE_AT] = math.nan
    ctx[base + L.S_WS] = ws
    return ctx


def counting_walls(calls):
    def df(x, p):
        calls.append(x)
        return A * x + 3.0 * x * x

    return ((f,), (df,), (d2f,))


def test_memo_gives_the_bits_of_the_call_with_one_call_less():
    calls: list = []
    walls = counting_walls(calls)
    with_memo = block(0.01)
    first = K.gap_rate(with_memo, (), walls, 0, 0.012, 0.01, 0.3, -0.2)
    s = with_memo[L.SURF + L.S_WS]
    assert with_memo[L.SURF + L.S_SLOPE_AT] == s
    calls.clear()
    again = K.gap_rate(with_memo, (), walls, 0, 0.0121, 0.01, 0.3, -0.2)
    # the same inversion from a block without the memo
    fresh = block(s)
    plain_calls: list = []
    expected = K.gap_rate(fresh, (), counting_walls(plain_calls), 0, 0.0121, 0.01, 0.3, -0.2)
    assert [v.hex() for v in again] == [v.hex() for v in expected]
    assert with_memo[L.SURF + L.S_WS] == fresh[L.SURF + L.S_WS]
    assert calls[0] != s and plain_calls[0] == s  # the memo stood for f'(s) at the start
    assert len(calls) == len(plain_calls) - 1
    assert first != again


def test_no_memo_at_zero_nor_from_a_handed_out_block():
    calls: list = []
    walls = counting_walls(calls)
    ctx = block(0.0)
    ctx[L.SURF + L.S_SLOPE_AT], ctx[L.SURF + L.S_SLOPE] = -0.0, 123.0
    K.gap_accel(ctx, (), walls, 0, 0.0, 0.01, 0.0, 0.0, 0.0, -9.81)
    assert calls[0] == 0.0  # called at s = 0, the memo not read

    from billiard.geometry.surfaces import OffsetWall
    from billiard.geometry.walls import Wall

    wall = Wall(0, -1.0, 1.0, (), f, walls[1][0], d2f, None, None, None, None)
    surface = OffsetWall(wall, R, 0)
    surface.gap_rate(0.01, 0.01, 0.0, 0.0, [0.01, 0.0])
    assert not math.isnan(surface.ctx[L.SURF + L.S_SLOPE_AT])  # its own memo
    assert math.isnan(surface.block()[L.S_SLOPE_AT])  # not handed out
