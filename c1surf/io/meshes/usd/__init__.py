"""USD (``.usd``, ``.usda``, ``.usdc``, ``.usdz``) through usd-core (``pip install c1surf[usd]``): ``UsdGeom.Mesh``
prims with their subdivision tags in (``read``), the fit's cage and tessellations out (``write``)."""
