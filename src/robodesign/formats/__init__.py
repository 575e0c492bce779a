"""Files and the typed specs they become: CoBRA modules, tasks, solutions, costs and benchmark IDs, URDF;
geometry, tolerated poses and assemblies as plain, picklable data."""
