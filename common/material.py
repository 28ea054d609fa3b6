"""Isotropic linear-elastic material (SI units: E in Pa, density in kg/m^3)."""

from dataclasses import dataclass


@dataclass(frozen=True)
class Material:
    """Isotropic linear-elastic material (SI units)."""

    E: float = 210e9  #: Young's modulus [Pa]
    nu: float = 0.3  #: Poisson's ratio [-]
    rho: float = 7850.0  #: density [kg/m^3]

    def __post_init__(self) -> None:
        if not self.E > 0:
            raise ValueError(f"Young's modulus E must be positive, got {self.E} Pa")
        if not -1.0 < self.nu < 0.5:
            raise ValueError(f"Poisson's ratio nu must lie in (-1, 0.5), got {self.nu}")
        if not self.rho > 0:
            raise ValueError(f"density rho must be positive, got {self.rho} kg/m^3")

    @property
    def lmbda(self) -> float:
        """First Lamé parameter [Pa]."""
        return self.E * self.nu / ((1 + self.nu) * (1 - 2 * self.nu))

    @property
    def mu(self) -> float:
        """Shear modulus [Pa]."""
        return self.E / (2 * (1 + self.nu))
