import pytest
from tests.test_fmus import test_each_fmu_runs_from_its_file_alone_in_a_fresh_process as real

@pytest.mark.parametrize("i", range(8))
def test_real(fmu_paths, tmp_path, i):
    real(fmu_paths, tmp_path)
