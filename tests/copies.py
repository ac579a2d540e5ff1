"""Lines of a script run under numba's CUDA simulator that count the bytes copied back
from the device: every ``copy_to_host`` adds its size to the list ``copied`` (the GPU
path's copies, per trajectory, are part of its contract: docs/design.md, "What comes
back from the GPU")."""

COUNT_COPIES = """
from numba.cuda.simulator.cudadrv import devicearray
copied = []
to_host = devicearray.FakeCUDAArray.copy_to_host
def counted(self, ary=None, stream=0):
    copied.append(self.nbytes)
    return to_host(self, ary, stream)
devicearray.FakeCUDAArray.copy_to_host = counted
"""
